#include "nestlight/converters/byte_source.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

class MappedFile final : public ByteSource {
 public:
  explicit MappedFile(std::string path) : path_(std::move(path)) {
    int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(path_, "", std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd);
      throw Error(path_, "", "not a regular file");
    }
    size_ = static_cast<size_t>(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        int e = errno;
        ::close(fd);
        throw Error(path_, "", std::string("cannot map: ") + std::strerror(e));
      }
      data_ = static_cast<const uint8_t*>(p);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    ::close(fd);
  }
  ~MappedFile() override {
    if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
  }
  const uint8_t* data() const override { return data_; }
  size_t size() const override { return size_; }
  const std::string& name() const override { return path_; }
  void releaseBefore(size_t offset) override {
    static const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    size_t end = std::min(offset, size_) / page * page;
    // Only in large steps: madvise is a system call.
    if (data_ && end > released_ + (size_t(64) << 20)) {
      ::madvise(const_cast<uint8_t*>(data_) + released_, end - released_, MADV_DONTNEED);
      released_ = end;
    }
    if (offset < released_) released_ = 0;  // a rewind
  }

 private:
  std::string path_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t released_ = 0;
};

class MemorySource final : public ByteSource {
 public:
  MemorySource(std::string name, std::vector<uint8_t> bytes)
      : name_(std::move(name)), bytes_(std::move(bytes)) {}
  const uint8_t* data() const override { return bytes_.data(); }
  size_t size() const override { return bytes_.size(); }
  const std::string& name() const override { return name_; }

 private:
  std::string name_;
  std::vector<uint8_t> bytes_;
};

class BorrowedSource final : public ByteSource {
 public:
  BorrowedSource(std::string name, const uint8_t* data, size_t size)
      : name_(std::move(name)), data_(data), size_(size) {}
  const uint8_t* data() const override { return data_; }
  size_t size() const override { return size_; }
  const std::string& name() const override { return name_; }

 private:
  std::string name_;
  const uint8_t* data_;
  size_t size_;
};

}  // namespace

std::shared_ptr<ByteSource> mapFile(const std::string& path) {
  return std::make_shared<MappedFile>(path);
}
std::shared_ptr<ByteSource> memorySource(std::string name, std::vector<uint8_t> bytes) {
  return std::make_shared<MemorySource>(std::move(name), std::move(bytes));
}
std::shared_ptr<ByteSource> borrowedSource(std::string name, const uint8_t* data, size_t size) {
  return std::make_shared<BorrowedSource>(std::move(name), data, size);
}

}  // namespace nestlight
