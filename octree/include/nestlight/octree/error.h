// Errors and invariants.
//
// User input problems (a bad file, a bad flag) are reported as nestlight::Error, which names the
// file and the position (byte offset or line) so that the user can find the fault. Broken internal
// invariants are programming errors and abort through NL_CHECK, as pbrt's CHECK does.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace nestlight {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& reason) : std::runtime_error(reason), reason_(reason) {}
  // `position` is human readable: "byte 1234", "line 17", "vertex 5 property 'x'".
  Error(std::string file, std::string position, const std::string& reason)
      : std::runtime_error(format(file, position, reason)),
        file_(std::move(file)),
        position_(std::move(position)),
        reason_(reason) {}

  const std::string& file() const { return file_; }
  const std::string& position() const { return position_; }
  const std::string& reason() const { return reason_; }

  static std::string atByte(uint64_t offset) { return "byte " + std::to_string(offset); }
  static std::string atLine(uint64_t line) { return "line " + std::to_string(line); }

 private:
  static std::string format(const std::string& file, const std::string& position,
                            const std::string& reason) {
    std::string s = file;
    if (!position.empty()) s += (s.empty() ? "" : ": ") + position;
    return s + (s.empty() ? "" : ": ") + reason;
  }
  std::string file_, position_, reason_;
};

[[noreturn]] void checkFailed(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace nestlight

#define NL_CHECK(cond)                                                               \
  do {                                                                               \
    if (!(cond)) ::nestlight::checkFailed(#cond, __FILE__, __LINE__, std::string()); \
  } while (0)
#define NL_CHECK_MSG(cond, msg)                                              \
  do {                                                                       \
    if (!(cond)) ::nestlight::checkFailed(#cond, __FILE__, __LINE__, (msg)); \
  } while (0)
