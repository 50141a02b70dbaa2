// The builder as a job of several ranks (`mpirun -n N nestlight convert --mpi`). The passes are
// the single process's (builder.cpp); what changes is who does each part and what the ranks tell
// each other:
// - inputs are dealt to ranks by size; each rank counts its own, and the counting grids are summed
//   (allreduce), so every rank plans the same chunks;
// - the chunks, in Morton order, are cut into one contiguous range per rank holding as many
//   counted points as the others; a rank distributes its inputs' points into its own chunks'
//   files and into one outbox per other rank, then the outboxes are exchanged (alltoallv) in
//   rounds whose size the memory budget bounds;
// - each rank indexes its chunks and merges the levels above them as far as every chunk below a
//   node is its own; rank 0 merges the nodes above ranges (the shared nodes) from the other
//   ranks' samples of the nodes just below them;
// - each rank's nodes are in its own part of the payload; the parts are copied into the output at
//   offsets agreed from their sizes, and rank 0 writes the hierarchy and the metadata and commits.
// A node's content is a function of its subtree's points alone (builder.cpp), so the octree holds
// the same points in the same nodes for any number of ranks; only the order of the nodes in the
// payload differs. See docs/DISTRIBUTED.md.
#include <fcntl.h>

#include "builder_passes.h"

namespace nestlight::build_passes {

namespace {

// Plain values in and out of the byte messages the ranks exchange.
struct ByteWriter {
  std::vector<uint8_t> bytes;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put(const uint8_t* p, size_t n) { bytes.insert(bytes.end(), p, p + n); }
};

struct ByteReader {
  const std::vector<uint8_t>& bytes;
  size_t at = 0;
  template <class T>
  T get() {
    NL_CHECK_MSG(at + sizeof(T) <= bytes.size(), "a message between ranks ends early");
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  const uint8_t* take(size_t n) {
    NL_CHECK_MSG(at + n <= bytes.size(), "a message between ranks ends early");
    const uint8_t* p = bytes.data() + at;
    at += n;
    return p;
  }
  bool done() const { return at == bytes.size(); }
};

void putKey(ByteWriter& w, const NodeKey& k) {
  w.put(k.level), w.put(k.x), w.put(k.y), w.put(k.z);
}
NodeKey getKey(ByteReader& r) {
  NodeKey k;
  k.level = r.get<uint32_t>(), k.x = r.get<uint32_t>(), k.y = r.get<uint32_t>();
  k.z = r.get<uint32_t>();
  return k;
}

std::vector<uint8_t> jsonBytes(const nlohmann::json& j) {
  const std::string s = j.dump();
  return {s.begin(), s.end()};
}
nlohmann::json bytesJson(const std::vector<uint8_t>& b) {
  return nlohmann::json::parse(std::string(b.begin(), b.end()));
}

}  // namespace

fs::path scratchFolder(const BuildOptions& o, const fs::path& staged, int rank, bool distributed) {
  const std::string r = distributed ? "rank-" + std::to_string(rank) : "chunks";
  if (o.scratch.empty()) return staged / (r + ".tmp");
  // Named after the output (its absolute path hashed), so that conversions of other outputs into
  // the same scratch folder never meet and a rerun of this one finds what a killed run left.
  const std::string out = fs::absolute(o.output).lexically_normal().string();
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)std::hash<std::string>()(out));
  return o.scratch / ("nestlight-" + o.output.filename().string() + "-" + hash + "-" + r + ".tmp");
}

void Builder::dealSources() {
  // Each input of more than a rank's share of the bytes is cut into parts, one per share, where
  // its reader can be restricted to a range (an uncompressed LAS file's records); then the
  // pieces go largest first to the least loaded rank (a greedy deal within 4/3 of the best,
  // Graham's bound), the parts of one input to different ranks. Ties go to the lower rank and
  // pieces of equal size in path order, so every rank computes the same deal.
  struct Piece {
    size_t source;
    uint64_t part, parts, bytes;
  };
  const uint64_t n = uint64_t(ranks());
  uint64_t total = 0;
  for (const auto& s : sources_) {
    // Whole again (a run started over keeps its readers): every rank deals the same sizes.
    if (const uint64_t units = s.reader->splitUnits(); units > 1) s.reader->restrictTo(0, units);
    total += s.reader->bytesTotal();
  }
  const uint64_t share = std::max<uint64_t>(total / n, 1);
  std::vector<Piece> pieces;
  for (size_t i = 0; i < sources_.size(); ++i) {
    const uint64_t bytes = sources_[i].reader->bytesTotal(),
                   units = sources_[i].reader->splitUnits();
    // At least one piece (an empty file has no unit to split), at most one per rank and unit.
    const uint64_t parts = std::clamp<uint64_t>((bytes + share - 1) / share, 1,
                                                std::max<uint64_t>(1, std::min(n, units)));
    for (uint64_t p = 0; p < parts; ++p) pieces.push_back({i, p, parts, bytes / parts});
  }
  std::stable_sort(pieces.begin(), pieces.end(), [&](const Piece& a, const Piece& b) {
    if (a.bytes != b.bytes) return a.bytes > b.bytes;
    const std::string &pa = sources_[a.source].reader->header().path,
                      &pb = sources_[b.source].reader->header().path;
    if (pa != pb) return pa < pb;
    return a.source != b.source ? a.source < b.source : a.part < b.part;
  });
  std::vector<uint64_t> load(n, 0);
  std::vector<std::set<size_t>> holds(n);
  for (auto& s : sources_) s.owned = false;
  for (const Piece& pc : pieces) {
    size_t r = SIZE_MAX;
    for (size_t k = 0; k < n; ++k)
      if (!holds[k].count(pc.source) && (r == SIZE_MAX || load[k] < load[r])) r = k;
    load[r] += std::max<uint64_t>(pc.bytes, 1);
    holds[r].insert(pc.source);
    if (int(r) != rank()) continue;
    SourceState& s = sources_[pc.source];
    s.owned = true;
    if (pc.parts > 1) {
      const uint64_t units = s.reader->splitUnits();
      s.reader->restrictTo(units * pc.part / pc.parts, units * (pc.part + 1) / pc.parts);
    }
  }
}

void Builder::assignChunks() {
  // Contiguous in Morton order, so that most nodes above the chunks have all their chunks on
  // one rank and are merged there; the cut points fall where the running count passes k/N of
  // the total (chunks never split, so ranges differ by up to a chunk).
  uint64_t total = 0;
  for (const Chunk& c : chunks_) total += c.points;
  const uint64_t n = uint64_t(ranks());
  uint64_t before = 0;
  for (Chunk& c : chunks_) {
    // The chunk goes to the rank whose share holds its middle point.
    const uint64_t mid = before + c.points / 2;
    c.owner = total ? int(std::min<uint64_t>(n - 1, (mid * n) / total)) : 0;
    before += c.points;
    if (c.owner != rank()) c.file = tmp_ / ("outbox-" + std::to_string(c.owner) + ".bin");
  }
}

void Builder::exchangeRecords() {
  const size_t rec = 12 + stride_;
  const int n = ranks(), me = rank();
  // A round receives at most a quarter of the budget (and under MPI's 2 GiB per call): each
  // pair of ranks moves that divided by the ranks, in whole records.
  const uint64_t round = std::min<uint64_t>(opt_.memoryBytes / 4, uint64_t(1) << 30);
  const size_t perPair = std::max<size_t>(1, size_t(round / uint64_t(n) / rec)) * rec;
  std::vector<FILE*> outbox(static_cast<size_t>(n), nullptr);
  uint64_t pending = 0;
  for (int d = 0; d < n; ++d) {
    if (d == me) continue;
    const fs::path p = tmp_ / ("outbox-" + std::to_string(d) + ".bin");
    if (!fs::exists(p)) continue;
    pending += fs::file_size(p);
    outbox[size_t(d)] = std::fopen(p.c_str(), "rb");
    if (!outbox[size_t(d)]) throw Error(p.string(), "", "cannot read outbox file");
  }
  progress_.begin("exchange", comm_->sum(pending), "bytes");
  std::vector<std::vector<uint8_t>> send(static_cast<size_t>(n));
  for (;;) {
    uint64_t sent = 0;
    for (int d = 0; d < n; ++d) {
      send[size_t(d)].clear();
      FILE* f = outbox[size_t(d)];
      if (!f) continue;
      send[size_t(d)].resize(perPair);
      const size_t got = std::fread(send[size_t(d)].data(), 1, perPair, f);
      send[size_t(d)].resize(got - got % rec);
      sent += send[size_t(d)].size();
      if (got < perPair) {
        std::fclose(f);
        outbox[size_t(d)] = nullptr;
      }
    }
    bytesSent_ += sent;
    const std::vector<std::vector<uint8_t>> recv = comm_->alltoallv(send);
    // Received records go to their chunks' files, grouped by chunk (one open per chunk).
    std::map<uint32_t, std::vector<const uint8_t*>> byChunk;
    uint64_t got = 0;
    for (const auto& from : recv) {
      NL_CHECK_MSG(from.size() % rec == 0, "a rank sent a partial record");
      for (size_t k = 0; k < from.size(); k += rec) {
        uint32_t q[3];
        std::memcpy(q, &from[k], 12);
        const int32_t c = cellChunk_[gridCell(q)];
        NL_CHECK_MSG(c >= 0 && chunks_[size_t(c)].owner == me, "a record reached the wrong rank");
        byChunk[uint32_t(c)].push_back(&from[k]);
      }
      got += from.size();
    }
    for (const auto& [c, recs] : byChunk) {
      FILE* f = std::fopen(chunks_[c].file.c_str(), "ab");
      bool ok = f != nullptr;
      for (const uint8_t* r : recs) ok = ok && std::fwrite(r, 1, rec, f) == rec;
      if (f) ok = std::fclose(f) == 0 && ok;
      if (!ok) throw Error(chunks_[c].file.string(), "", "cannot write chunk file (disk full?)");
    }
    progress_.advance(got, got / rec);
    // Every rank takes part in every round until no rank has anything left.
    if (comm_->sum(sent) == 0) break;
  }
  for (FILE* f : outbox)
    if (f) std::fclose(f);
  for (int d = 0; d < n; ++d) {
    std::error_code ec;
    fs::remove(tmp_ / ("outbox-" + std::to_string(d) + ".bin"), ec);
  }
  progress_.end();
  // This rank's chunks hold what it read of them and what it received: their files say how much.
  for (Chunk& c : chunks_) {
    std::error_code ec;
    c.points = c.owner == me && fs::exists(c.file, ec) ? fs::file_size(c.file) / rec : 0;
    if (c.owner == me) indexed_ += c.points;
  }
}

void Builder::mergeTopDistributed() {
  // Which rank holds each chunk root's sample.
  ByteWriter mine;
  for (const NodeKey& k : pending_) putKey(mine, k);
  std::map<NodeKey, int> holder;
  const auto all = comm_->allgather(mine.bytes);
  for (int r = 0; r < ranks(); ++r) {
    ByteReader in{all[size_t(r)]};
    while (!in.done()) holder[getKey(in)] = r;
  }
  // The nodes above them: merged where every chunk below is one rank's, else on rank 0 (-1).
  std::map<NodeKey, int> mergedBy;
  for (const auto& [k, r] : holder)
    for (uint32_t l = 0; l < k.level; ++l) {
      auto [it, added] = mergedBy.emplace(k.ancestor(l), r);
      if (!added && it->second != r) it->second = -1;
    }
  std::set<NodeKey> local, shared;
  for (const auto& [k, r] : mergedBy) {
    if (r == rank()) local.insert(k);
    if (r < 0) shared.insert(k);
  }
  mergeNodes(local);
  // This rank's samples just below the shared nodes go to rank 0: the nodes it holds now whose
  // parent is shared.
  std::vector<std::vector<uint8_t>> send(static_cast<size_t>(ranks()));
  if (rank() != 0) {
    ByteWriter w;
    std::set<NodeKey> held;
    {
      std::lock_guard<std::mutex> lock(pendingMutex_);
      held = pending_;
    }
    for (const NodeKey& k : held) {
      if (k.level == 0 || !shared.count(k.parent()) || !fs::exists(provisionalFile(k))) continue;
      const fs::path f = provisionalFile(k);
      const uint64_t bytes = fs::file_size(f);
      putKey(w, k);
      w.put(subtreePoints_.at(k));
      w.put(bytes);
      std::vector<uint8_t> data(bytes);
      FILE* in = std::fopen(f.c_str(), "rb");
      const bool ok = in && std::fread(data.data(), 1, bytes, in) == bytes;
      if (in) std::fclose(in);
      if (!ok) throw Error(f.string(), "", "cannot read a provisional sample");
      w.put(data.data(), data.size());
      bytesSent_ += bytes;
      fs::remove(f);
    }
    send[0] = std::move(w.bytes);
  }
  const auto recv = comm_->alltoallv(send);
  if (rank() == 0) {
    for (int r = 1; r < ranks(); ++r) {
      ByteReader in{recv[size_t(r)]};
      while (!in.done()) {
        const NodeKey k = getKey(in);
        const uint64_t subtree = in.get<uint64_t>(), bytes = in.get<uint64_t>();
        const uint8_t* data = in.take(bytes);
        const fs::path f = provisionalFile(k);
        FILE* out = std::fopen(f.c_str(), "wb");
        const bool ok = out && std::fwrite(data, 1, bytes, out) == bytes;
        if (out && std::fclose(out) != 0) throw Error(f.string(), "", "cannot write (disk full?)");
        if (!ok) throw Error(f.string(), "", "cannot write a provisional sample (disk full?)");
        std::lock_guard<std::mutex> lock(pendingMutex_);
        pending_.insert(k);
        subtreePoints_[k] = subtree;
      }
    }
    mergeNodes(shared);
  }
  // The root: rank 0's when shared (or when no rank has a point), else the one rank's that
  // merged (or indexed) it.
  int rootWriter = 0;
  if (const auto it = mergedBy.find(NodeKey::root()); it != mergedBy.end())
    rootWriter = std::max(it->second, 0);
  else if (const auto h = holder.find(NodeKey::root()); h != holder.end())
    rootWriter = h->second;
  if (rank() == rootWriter) writeRoot();
}

void Builder::reduceTotals() {
  // Accounting, bounds and each source's counts and warnings, from the rank that read it.
  nlohmann::json mine;
  mine["input"] = accounting_.input;
  mine["merged"] = accounting_.duplicatesMerged;
  mine["stored"] = stored_.load();
  mine["rejected"] = accounting_.rejected;
  mine["bounds"] = {meta_.bounds.min.x, meta_.bounds.min.y, meta_.bounds.min.z,
                    meta_.bounds.max.x, meta_.bounds.max.y, meta_.bounds.max.z};
  nlohmann::json sources = nlohmann::json::array();
  for (size_t i = 0; i < sources_.size(); ++i) {
    const SourceState& s = sources_[i];
    if (!s.owned) continue;
    sources.push_back({{"index", i},
                       {"read", s.read},
                       {"unreadable", s.unreadable},
                       {"outside", s.outsideDeclared},
                       {"outside_max", s.outsideMax},
                       {"warnings", s.reader->warnings()}});
  }
  mine["sources"] = sources;
  uint64_t chunks = 0;
  for (const Chunk& c : chunks_) chunks += c.owner == rank();
  mine["chunks"] = chunks;
  const auto all = comm_->allgather(jsonBytes(mine));
  // An input read in parts by several ranks: its counts add up, its warnings are merged.
  for (SourceState& st : sources_) {
    st.read = st.unreadable = st.outsideDeclared = 0;
    st.outsideMax = 0;
    st.remoteWarnings = std::vector<std::string>();
  }
  accounting_ = Accounting{};
  uint64_t stored = 0;
  Box3d bounds;
  for (const auto& b : all) {
    const nlohmann::json j = bytesJson(b);
    accounting_.input += j["input"].get<uint64_t>();
    accounting_.duplicatesMerged += j["merged"].get<uint64_t>();
    stored += j["stored"].get<uint64_t>();
    chunksTotal_ += j["chunks"].get<uint64_t>();
    for (const auto& [k, v] : j["rejected"].items()) accounting_.rejected[k] += v.get<uint64_t>();
    const auto& bb = j["bounds"];
    Box3d r;
    // An empty box (a rank that read no point) has infinite corners, which JSON writes as null.
    if (!bb[0].is_null() && !bb[3].is_null()) {
      r.extend(bb[0].get<double>(), bb[1].get<double>(), bb[2].get<double>());
      r.extend(bb[3].get<double>(), bb[4].get<double>(), bb[5].get<double>());
    }
    bounds.extend(r);
    for (const auto& s : j["sources"]) {
      SourceState& st = sources_.at(s["index"].get<size_t>());
      st.read += s["read"].get<uint64_t>();
      st.unreadable += s["unreadable"].get<uint64_t>();
      st.outsideDeclared += s["outside"].get<uint64_t>();
      st.outsideMax = std::max(st.outsideMax, s["outside_max"].get<double>());
      for (const std::string& w : s["warnings"].get<std::vector<std::string>>())
        if (std::find(st.remoteWarnings->begin(), st.remoteWarnings->end(), w) ==
            st.remoteWarnings->end())
          st.remoteWarnings->push_back(w);
    }
  }
  stored_ = stored;
  meta_.bounds = bounds;
}

void Builder::assembleOutput(const fs::path& staged) {
  const std::vector<NodeRecord> nodes = writer_->finishPart();
  const fs::path part = tmp_ / "part" / "octree.bin.tmp";
  const uint64_t bytes = fs::file_size(part);
  // Offsets: the parts in rank order.
  std::vector<uint64_t> sizes(static_cast<size_t>(ranks()), 0);
  sizes[size_t(rank())] = bytes;
  comm_->allreduceSum(sizes);
  uint64_t base = 0, total = 0;
  for (int r = 0; r < ranks(); ++r) (r < rank() ? base : total) += sizes[size_t(r)];
  total += base;
  const fs::path payload = staged / "octree.bin.tmp";
  if (rank() == 0) {
    const int fd = ::open(payload.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const bool ok = fd >= 0 && ::ftruncate(fd, off_t(total)) == 0;
    if (fd >= 0) ::close(fd);
    if (!ok) throw Error(payload.string(), "", std::string("cannot create: ") + strerror(errno));
  }
  comm_->barrier();
  {
    const int in = ::open(part.c_str(), O_RDONLY | O_CLOEXEC);
    const int out = ::open(payload.c_str(), O_WRONLY | O_CLOEXEC);
    if (in < 0 || out < 0) {
      if (in >= 0) ::close(in);
      if (out >= 0) ::close(out);
      throw Error(payload.string(), "", std::string("cannot open: ") + strerror(errno));
    }
    std::vector<uint8_t> buf(8 << 20);
    uint64_t at = 0;
    while (at < bytes) {
      const ssize_t got =
          ::pread(in, buf.data(), std::min<uint64_t>(buf.size(), bytes - at), off_t(at));
      ssize_t done = 0;
      while (got > 0 && done < got) {
        const ssize_t w =
            ::pwrite(out, buf.data() + done, size_t(got - done), off_t(base + at + uint64_t(done)));
        if (w <= 0) break;
        done += w;
      }
      if (got <= 0 || done < got) {
        const int e = errno;
        ::close(in), ::close(out);
        throw Error(payload.string(), "",
                    std::string("cannot write this rank's part (disk full?): ") + strerror(e));
      }
      at += uint64_t(got);
    }
    const bool synced = ::fsync(out) == 0;
    ::close(in), ::close(out);
    if (!synced) throw Error(payload.string(), "", "fsync failed");
  }
  // The nodes, at their offsets in the whole payload, to rank 0.
  std::vector<std::vector<uint8_t>> send(static_cast<size_t>(ranks()));
  ByteWriter w;
  for (NodeRecord n : nodes) {
    n.byteOffset += base;
    w.put(n);
  }
  send[0] = std::move(w.bytes);
  comm_->barrier();  // every part is in place before the octree is made complete
  const auto recv = comm_->alltoallv(send);
  if (rank() != 0) return;
  std::vector<NodeRecord> all;
  for (const auto& from : recv) {
    ByteReader in{from};
    while (!in.done()) all.push_back(in.get<NodeRecord>());
  }
  OctreeWriter::finishAssembled(staged, meta_, std::move(all), total);
}

nlohmann::json Builder::gatherRankReports(const BuildReport& mine) {
  uint64_t inputBytes = 0;
  for (const auto& s : sources_)
    if (s.owned) inputBytes += s.reader->bytesTotal();
  const nlohmann::json j = {{"rank", rank()},
                            {"input_bytes", inputBytes},
                            {"points_indexed", indexed_},
                            {"bytes_sent", bytesSent_},
                            {"peak_rss_bytes", mine.peakRssBytes},
                            {"phases", mine.phases}};
  const auto all = comm_->allgather(jsonBytes(j));
  nlohmann::json out = nlohmann::json::array();
  for (const auto& b : all) out.push_back(bytesJson(b));
  return out;
}

}  // namespace nestlight::build_passes
