// Shared helpers for the unit tests: temporary folders, the shared data folder, running the CLI.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace nestlight::test {

// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// ../shared/data beside the checkout; empty when absent.
std::filesystem::path sharedData();

// Runs the built `nestlight` with `args`; returns the exit code, stdout+stderr in `output`.
int runCli(const std::string& args, std::string* output = nullptr);

void writeFile(const std::string& path, const std::string& bytes);
std::string readFile(const std::string& path);

}  // namespace nestlight::test

// Skips the test with a message when a file of ../shared/data is missing.
#define NL_REQUIRE_SHARED(rel)                                                         \
  do {                                                                                 \
    if (!std::filesystem::exists(::nestlight::test::sharedData() / (rel)))             \
      GTEST_SKIP() << "../shared/data/" << (rel) << " is absent; skipping real-data test"; \
  } while (0)
