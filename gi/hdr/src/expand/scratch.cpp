// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4: the scratch file
// that holds every point's HDR colour so far between the passes (16 bytes a point), so that
// memory stays bounded whatever the scan's size. Removed when the expansion ends, however.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "expand/expansion.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr::expand {

Scratch::Scratch(const fs::path& path, uint64_t points) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw Error(path.string(), "",
                std::string("cannot create the scratch file: ") + std::strerror(errno));
  if (::ftruncate(fd_, off_t(points * sizeof(ScratchRecord))) != 0)
    throw Error(path.string(), "",
                std::string("cannot size the scratch file: ") + std::strerror(errno));
}

Scratch::~Scratch() {
  ::close(fd_);
  std::error_code ec;
  fs::remove(path_, ec);
}

void Scratch::read(uint64_t first, size_t count, std::vector<ScratchRecord>& out) const {
  out.resize(count);
  io(false, first, count, out.data());
}

void Scratch::write(uint64_t first, const std::vector<ScratchRecord>& in) {
  io(true, first, in.size(), const_cast<ScratchRecord*>(in.data()));
}

void Scratch::io(bool write, uint64_t first, size_t count, ScratchRecord* data) const {
  uint8_t* p = reinterpret_cast<uint8_t*>(data);
  size_t left = count * sizeof(ScratchRecord);
  uint64_t off = first * sizeof(ScratchRecord);
  while (left > 0) {
    const ssize_t r =
        write ? ::pwrite(fd_, p, left, off_t(off)) : ::pread(fd_, p, left, off_t(off));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0)
      throw Error(path_.string(), Error::atByte(off),
                  std::string("scratch I/O failed: ") + std::strerror(errno));
    p += r, left -= size_t(r), off += uint64_t(r);
  }
}

}  // namespace nestlight::gi::hdr::expand
