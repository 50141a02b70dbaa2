// Read-only bytes of an input file, or of a buffer (fuzz targets, tests).
//
// Files are memory-mapped: readers parse in place without copying. Readers call releaseBefore()
// as they advance so that pages already parsed leave the process's resident set; without it a
// 3 GB input would count 3 GB towards peak RSS even though the converter holds a bounded amount.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace nestlight {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual const uint8_t* data() const = 0;
  virtual size_t size() const = 0;
  // The name used in error messages (the path for files).
  virtual const std::string& name() const = 0;
  // Hint that bytes before `offset` will not be read again until a rewind.
  virtual void releaseBefore(size_t /*offset*/) {}
};

// Maps `path`; throws nestlight::Error naming the file when it cannot be opened.
std::shared_ptr<ByteSource> mapFile(const std::string& path);
std::shared_ptr<ByteSource> memorySource(std::string name, std::vector<uint8_t> bytes);
// Does not copy: `data` must outlive the source (fuzz targets).
std::shared_ptr<ByteSource> borrowedSource(std::string name, const uint8_t* data, size_t size);

}  // namespace nestlight
