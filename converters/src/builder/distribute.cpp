// The builder's counting and distribution passes: points counted on a coarse grid, cells merged
// into chunks under the memory budget, points written to their chunk's file (Schütz, Ohrhallinger,
// Wimmer, "Fast Out-of-Core Octree Generation for Massive Point Clouds", 2020).
#include "builder_passes.h"

namespace nestlight::build_passes {

// Reads every source, runs `work` on batches in parallel and `collect` in input order.
template <class Work, class Collect>
void Builder::readAll(const std::string& phase, Work work, Collect collect, size_t sampleStep) {
  uint64_t total = 0;
  for (auto& s : sources_)
    if (s.owned) total += s.reader->bytesTotal();
  progress_.begin(phase, total, "bytes");
  size_t current = 0;
  uint64_t consumedBefore = 0;
  for (auto& s : sources_) s.reader->rewind();
  // Batches between the stages are owned here until the last stage takes them: when a stage
  // throws (damaged input, a full disk), the pipeline drops the batches in flight, and they are
  // freed below rather than leaked.
  std::mutex liveMutex;
  std::unordered_set<Item*> live;
  auto adopt = [&](Item* it) {
    std::lock_guard<std::mutex> lock(liveMutex);
    live.insert(it);
  };
  auto release = [&](Item* it) {
    std::lock_guard<std::mutex> lock(liveMutex);
    live.erase(it);
  };
  try {
    tbb::parallel_pipeline(
        threads_ * 2,
        tbb::make_filter<void, Item*>(
            tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& fc) -> Item* {
              while (current < sources_.size()) {
                if (!sources_[current].owned) {  // another rank reads it
                  ++current;
                  continue;
                }
                auto item = std::make_unique<Item>();
                auto& r = *sources_[current].reader;
                // Compressed sources leave decoding to the
                // parallel stage (batch.finish()).
                const size_t weight = r.readDeferred(item->batch, kBatchPoints, sampleStep);
                if (weight) {
                  item->source = current;
                  item->weight = weight;
                  item->points =
                      (item->batch.pending ? item->batch.pendingPoints : item->batch.size()) *
                      weight;
                  progress_.advance(r.bytesConsumed() - consumedBefore, item->points);
                  consumedBefore = r.bytesConsumed();
                  adopt(item.get());
                  return item.release();
                }
                ++current;
                consumedBefore = 0;
              }
              fc.stop();
              return nullptr;
            }) &
            tbb::make_filter<Item*, Item*>(tbb::filter_mode::parallel,
                                           [&](Item* it) {
                                             if (it->batch.pending) {
                                               it->batch.finish();  // may throw on damage
                                               it->points = it->batch.size() * it->weight;
                                             }
                                             work(*it);
                                             return it;
                                           }) &
            tbb::make_filter<Item*, void>(tbb::filter_mode::serial_in_order, [&](Item* it) {
              release(it);
              std::unique_ptr<Item> own(it);
              collect(own);
            }));
  } catch (...) {
    for (Item* it : live) delete it;
    throw;
  }
  progress_.end();
}

// Quantises point k of the item; false (and counted) when rejected. Points beyond their
// header's bounds are kept, and counted in `outside` (the distribute pass) for a warning.
bool Builder::quantise(const SourceState& s, const double* p, uint32_t q[3], Accounting& acc,
                       std::pair<uint64_t, double>* outside) const {
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
    acc.rejected[reject::kNonFinite]++;
    return false;
  }
  if (outside && s.declared && !s.declared->contains(p[0], p[1], p[2], s.tolerance)) {
    double d = 0;
    for (int a = 0; a < 3; ++a)
      d = std::max({d, s.declared->min[a] - p[a], p[a] - s.declared->max[a]});
    outside->first++;
    outside->second = std::max(outside->second, d);
  }
  const int64_t maxInt = static_cast<int64_t>(meta_.cubeSize) - 1;
  for (int a = 0; a < 3; ++a) {
    // Truncation after +0.5 rounds every value at or above -0.5 (no libm call per coordinate);
    // anything outside the cube cannot be placed, and the cube is planned again.
    const double u = (p[a] - meta_.offset[a]) * invScale_[a] + 0.5;
    if (!(u >= 0 && u < double(maxInt) + 1)) {
      // Flagged, not thrown: an exception out of the pipeline's parallel stage would strand
      // the batches in flight. The pass ends and run() starts over (OutsideCube).
      outsideCube_.store(true, std::memory_order_relaxed);
      return false;
    }
    q[a] = static_cast<uint32_t>(std::min<int64_t>(static_cast<int64_t>(u), maxInt));
  }
  return true;
}

void Builder::countPass() {
  gridLevel_ = std::min(kGridLevel, cubeBits());
  gridShift_ = cubeBits() - gridLevel_;
  const size_t cells = size_t(1) << (3 * gridLevel_);
  // One shared grid of relaxed atomics (16 MiB): per-thread grids would grow with the core count
  // and escape the memory budget, and with sampled counting the increments are few.
  std::vector<std::atomic<uint64_t>> shared(cells);
  readAll(
      "count",
      [&](Item& it) {
        const SourceState& s = sources_[it.source];
        uint32_t q[3];
        for (size_t k = 0, n = it.batch.size(); k < n; ++k)
          if (quantise(s, &it.batch.xyz[3 * k], q, it.acc))
            shared[gridCell(q)].fetch_add(it.weight, std::memory_order_relaxed);
      },
      [](std::unique_ptr<Item>&) {},
      // Counts only plan the chunks (a chunk that turns out too large is split later), so a
      // sample of the points is enough where a reader can skip cheaply.
      kCountSampleStep);
  std::vector<uint64_t> counts(cells);
  for (size_t i = 0; i < cells; ++i) counts[i] = shared[i].load(std::memory_order_relaxed);
  std::vector<std::atomic<uint64_t>>().swap(shared);
  // Each rank counted its own inputs: the sum is the same grid on every rank, so every rank plans
  // the same chunks.
  if (distributed()) comm_->allreduceSum(counts);

  // Chunks: top-down, the largest nodes of the counting pyramid that fit the budget.
  std::vector<std::vector<uint64_t>> pyramid(gridLevel_ + 1);
  pyramid[gridLevel_] = std::move(counts);
  for (int l = static_cast<int>(gridLevel_) - 1; l >= 0; --l) {
    pyramid[l].assign(size_t(1) << (3 * l), 0);
    const uint32_t n = 1u << (l + 1);
    for (uint32_t x = 0; x < n; ++x)
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t z = 0; z < n; ++z)
          pyramid[l][((x >> 1) << (2 * l)) | ((y >> 1) << l) | (z >> 1)] +=
              pyramid[l + 1][(size_t(x) << (2 * (l + 1))) | (y << (l + 1)) | z];
  }
  maxChunkPoints_ = chunkBudget();
  cellChunk_.assign(cells, -1);
  std::function<void(NodeKey)> visit = [&](NodeKey k) {
    uint64_t c = pyramid[k.level][(size_t(k.x) << (2 * k.level)) | (k.y << k.level) | k.z];
    // Sampled counts can miss sparse cells, so nodes counted empty become chunks too; a chunk
    // that receives no points costs nothing later.
    if (c <= maxChunkPoints_ || k.level == gridLevel_) {
      int id = static_cast<int>(chunks_.size());
      chunks_.push_back({k, c, tmp_ / ("chunk-" + k.name() + ".bin"), 0});
      const uint32_t s = gridLevel_ - k.level, n = 1u << s;
      for (uint32_t x = 0; x < n; ++x)
        for (uint32_t y = 0; y < n; ++y)
          for (uint32_t z = 0; z < n; ++z) {
            uint32_t gx = (k.x << s) | x, gy = (k.y << s) | y, gz = (k.z << s) | z;
            cellChunk_[(size_t(gx) << (2 * gridLevel_)) | (gy << gridLevel_) | gz] = id;
          }
      return;
    }
    for (int i = 0; i < 8; ++i) visit(k.child(i));
  };
  visit(NodeKey::root());
}

uint64_t Builder::chunkBudget() const {
  if (opt_.inMemory) return UINT64_MAX;
  // Indexing holds a chunk's records twice (read and sorted) plus sort keys and index lists.
  const uint64_t perPoint = 2 * (12 + stride_) + 40 + (estimate_ ? 64 : 0);
  uint64_t b = opt_.memoryBytes / 2 / threads_ / perPoint;
  return std::max<uint64_t>(b, uint64_t(opt_.maxNodePoints) * 4);
}

void Builder::distributePass() {
  const size_t rec = 12 + stride_;
  for (auto& c : chunks_) c.points = 0;
  // A writer thread appends batches to the chunk files while the pipeline reads on; batches
  // wait in memory only up to a quarter of the budget.
  const size_t budget = std::max<size_t>(opt_.memoryBytes / 4, 16 << 20);
  std::mutex m;
  std::condition_variable cv;
  std::deque<std::unique_ptr<Item>> queue;
  size_t queued = 0;
  bool done = false;
  std::exception_ptr writeError;
  std::thread writer([&] {
    std::vector<std::unique_ptr<Item>> group;
    size_t groupBytes = 0;
    auto writeGroup = [&] {
      std::vector<std::vector<std::pair<const uint8_t*, size_t>>> perChunk(chunks_.size());
      for (auto& it : group) {
        size_t at = 0;
        for (auto& [c, n] : it->runs) {
          perChunk[c].emplace_back(it->records.get() + at, size_t(n) * rec);
          at += size_t(n) * rec;
        }
      }
      for (size_t c = 0; c < perChunk.size(); ++c) {
        if (perChunk[c].empty()) continue;
        FILE* f = std::fopen(chunks_[c].file.c_str(), "ab");
        bool ok = f != nullptr;
        for (auto& [p, n] : perChunk[c]) ok = ok && std::fwrite(p, 1, n, f) == n;
        if (f) ok = std::fclose(f) == 0 && ok;
        if (!ok) throw Error(chunks_[c].file.string(), "", "cannot write chunk file (disk full?)");
      }
      std::lock_guard<std::mutex> lock(m);
      queued -= groupBytes;
      group.clear();
      groupBytes = 0;
      cv.notify_all();
    };
    try {
      for (;;) {
        std::unique_ptr<Item> it;
        {
          std::unique_lock<std::mutex> lock(m);
          cv.wait(lock, [&] { return done || !queue.empty(); });
          if (queue.empty()) break;
          it = std::move(queue.front());
          queue.pop_front();
          cv.notify_all();  // a producer may wait for the queue to drain
        }
        groupBytes += it->recordBytes;
        group.push_back(std::move(it));
        if (groupBytes >= budget / 4) writeGroup();
      }
      writeGroup();
    } catch (...) {
      std::lock_guard<std::mutex> lock(m);
      writeError = std::current_exception();
      done = true;
      cv.notify_all();
    }
  });
  auto stopWriter = [&] {
    {
      std::lock_guard<std::mutex> lock(m);
      done = true;
      cv.notify_all();
    }
    writer.join();
  };
  try {
    readAll(
        "distribute",
        [&](Item& it) {
          const SourceState& s = sources_[it.source];
          const SourceHeader& h = s.reader->header();
          const size_t n = it.batch.size(), srcStride = h.layout.stride();
          thread_local std::vector<uint8_t> recs;
          thread_local std::vector<uint32_t> chunkOf;
          if (recs.size() < n * rec) recs.resize(n * rec);
          if (chunkOf.size() < n) chunkOf.resize(n);
          size_t kept = 0;
          it.acc.input = n;
          for (size_t k = 0; k < n; ++k) {
            const double* p = &it.batch.xyz[3 * k];
            uint32_t q[3];
            if (!quantise(s, p, q, it.acc, &it.outside)) continue;
            it.box.extend(p[0], p[1], p[2]);
            uint8_t* r = &recs[kept * rec];
            std::memcpy(r, q, 12);
            if (s.identity) {
              if (stride_) std::memcpy(r + 12, it.batch.attrs.data() + k * srcStride, stride_);
            } else
              mapAttributes(s, h.layout, it.batch.attrs.data() + k * srcStride, r + 12);
            chunkOf[kept] = static_cast<uint32_t>(cellChunk_[gridCell(q)]);
            ++kept;
          }
          // Group by chunk (counting sort, stable).
          std::vector<uint32_t> count(chunks_.size() + 1, 0);
          for (size_t k = 0; k < kept; ++k) count[chunkOf[k] + 1]++;
          for (size_t c = 0; c < chunks_.size(); ++c) {
            if (count[c + 1]) it.runs.emplace_back(static_cast<uint32_t>(c), count[c + 1]);
            count[c + 1] += count[c];
          }
          it.recordBytes = kept * rec;
          it.records.reset(new uint8_t[std::max<size_t>(it.recordBytes, 1)]);
          for (size_t k = 0; k < kept; ++k)
            std::memcpy(&it.records[size_t(count[chunkOf[k]]++) * rec], &recs[k * rec], rec);
          PointBatch().xyz.swap(it.batch.xyz);  // the input is no longer needed
          PointBatch().attrs.swap(it.batch.attrs);
        },
        [&](std::unique_ptr<Item>& it) {
          sources_[it->source].read += it->points;
          sources_[it->source].outsideDeclared += it->outside.first;
          sources_[it->source].outsideMax =
              std::max(sources_[it->source].outsideMax, it->outside.second);
          accounting_.add(it->acc);
          meta_.bounds.extend(it->box);
          for (auto& [c, n] : it->runs) chunks_[c].points += n;
          std::unique_lock<std::mutex> lock(m);
          if (writeError) std::rethrow_exception(writeError);
          cv.wait(lock, [&] {
            return queued + it->recordBytes <= budget || queue.empty() || writeError;
          });
          if (writeError) std::rethrow_exception(writeError);
          queued += it->recordBytes;
          queue.push_back(std::move(it));
          cv.notify_all();
        });
  } catch (...) {
    stopWriter();
    throw;
  }
  stopWriter();
  if (writeError) std::rethrow_exception(writeError);
  if (distributed()) exchangeRecords();
  // Points a source declares but could not decode (damaged LAZ chunks read leniently) are
  // input that was rejected, so that the accounting still covers every declared point.
  for (auto& src : sources_)
    if (!src.owned) {
      continue;
    } else if (const uint64_t lost = src.reader->pointsUnreadable()) {
      accounting_.input += lost;
      accounting_.rejected[reject::kUnreadable] += lost;
      src.unreadable = lost;
    }
  std::vector<int32_t>().swap(cellChunk_);
}

void Builder::mapAttributes(const SourceState& s, const PointLayout& src, const uint8_t* in,
                            uint8_t* out) const {
  for (size_t i = 0; i < layout_.size(); ++i) {
    const Attribute& a = layout_[i];
    uint8_t* o = out + layout_.offset(i);
    const auto& e = s.map.entries[i];
    if (e.copy) {
      std::memcpy(o, in + src.offset(e.src), a.byteSize());
    } else if (e.src >= 0) {
      const Attribute& sa = src[e.src];
      const size_t w = scalarSize(sa.type), ow = scalarSize(a.type);
      for (uint32_t c = 0; c < a.components; ++c)
        storeFromDouble(a.type, loadAsDouble(sa.type, in + src.offset(e.src) + c * w), o + c * ow);
    } else if (static_cast<int>(i) == normalIndex_ && estimate_) {
      const float nan = std::nanf("");
      for (int c = 0; c < 3; ++c) std::memcpy(o + 4 * c, &nan, 4);
    } else {
      std::memset(o, 0, a.byteSize());
    }
  }
}

void Builder::splitOversizedChunks() {
  // A counting cell denser than the budget (a dense statue in a city scan, a million duplicates)
  // is split into its octants, file to file, until it fits or cannot be split further.
  const size_t rec = 12 + stride_;
  for (size_t i = 0; i < chunks_.size(); ++i) {
    Chunk c = chunks_[i];
    if (c.points <= maxChunkPoints_ || (meta_.cubeSize >> c.key.level) <= 1) continue;
    const uint32_t half = (meta_.cubeSize >> c.key.level) >> 1;
    std::vector<FILE*> out(8, nullptr);
    std::vector<uint64_t> counts(8, 0);
    FILE* in = std::fopen(c.file.c_str(), "rb");
    if (!in) throw Error(c.file.string(), "", "cannot read chunk file");
    std::vector<uint8_t> buf(rec * 65536);
    size_t got;
    while ((got = std::fread(buf.data(), rec, 65536, in)) > 0) {
      for (size_t k = 0; k < got; ++k) {
        uint32_t q[3];
        std::memcpy(q, &buf[k * rec], 12);
        int ci = ((q[0] & half) ? 4 : 0) | ((q[1] & half) ? 2 : 0) | ((q[2] & half) ? 1 : 0);
        if (!out[ci]) {
          fs::path p = tmp_ / ("chunk-" + c.key.child(ci).name() + ".bin");
          out[ci] = std::fopen(p.c_str(), "wb");
          if (!out[ci]) throw Error(p.string(), "", "cannot create chunk file");
        }
        std::fwrite(&buf[k * rec], rec, 1, out[ci]);
        counts[ci]++;
      }
    }
    std::fclose(in);
    fs::remove(c.file);
    bool first = true;
    for (int ci = 0; ci < 8; ++ci) {
      if (!out[ci]) continue;
      std::fclose(out[ci]);
      Chunk child{c.key.child(ci), counts[ci], tmp_ / ("chunk-" + c.key.child(ci).name() + ".bin"),
                  c.owner};
      if (first) {
        chunks_[i] = child;
        first = false;
      } else {
        chunks_.push_back(child);
      }
    }
    --i;  // re-examine the chunk now at index i
  }
}

}  // namespace nestlight::build_passes
