// One validator for every JSON file Nestlight reads (octree metadata, scene files, camera paths):
// a value and its path, so an error names the file and the field ("scene.meshes[1].material.
// roughness: expected a number in [0, 1], got 1.5"), never a bare nlohmann exception.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace nestlight {

class JsonField {
 public:
  JsonField(const nlohmann::json& j, std::string path, std::string file)
      : j_(&j), path_(std::move(path)), file_(std::move(file)) {}

  // Throws nestlight::Error(file, path, why).
  [[noreturn]] void fail(const std::string& why) const;
  const nlohmann::json& value() const { return *j_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }

  bool has(const std::string& key) const { return j_->is_object() && j_->contains(key); }
  // The member `key`; a missing one (or a value that is not an object) fails naming it.
  JsonField at(const std::string& key) const;
  JsonField at(size_t i) const;
  // Fails on a member not in `allowed` (a typo must not be ignored) or a value that is no object.
  void expectObject(std::initializer_list<const char*> allowed) const;
  void expectObject(const std::vector<std::string>& allowed) const;
  size_t arraySize() const;

  double number(double lo = -INFINITY, double hi = INFINITY) const;  // finite, in [lo, hi]
  int64_t integer(int64_t lo, int64_t hi) const;
  uint64_t count() const;  // a non-negative integer
  bool boolean() const;
  std::string string() const;
  std::string choice(std::initializer_list<const char*> options) const;
  std::string choice(const std::vector<std::string>& options) const;
  std::array<double, 3> vec3(double lo = -INFINITY, double hi = INFINITY) const;

 private:
  const nlohmann::json* j_;
  std::string path_;
  std::string file_;
};

// Parses a JSON file; a syntax error names the file and the byte. Throws nestlight::Error.
nlohmann::json readJsonFile(const std::filesystem::path& file);

}  // namespace nestlight
