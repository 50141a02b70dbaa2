// A folder written beside its final place and swapped in only when complete.
//
// Replacing an octree (convert --overwrite) or a Potree dataset (export --force) in place loses
// the old one the moment the first file changes: a damaged input, a full disk or a kill then
// leaves neither. A StagedDirectory is built as a hidden sibling (".NAME.build-PID"), and
// commit() exchanges it with the final folder in one renameat2(RENAME_EXCHANGE) (two renames on
// a file system without it), then removes the old content. Until commit() the final folder is
// untouched; a staging folder that is not committed is removed by the destructor, and one left
// by a killed process is removed by the next StagedDirectory for the same place (and reported by
// `verify`). Entries of the final folder that are not the replaced content's own files (the
// user's notes beside an octree, a web page beside a Potree dataset) are carried into the new
// folder by hard links before the swap, so they survive it even if the process dies there.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace nestlight {

class StagedDirectory {
 public:
  // `finalDir`'s parent is created. `replaced` says which entries of an existing `finalDir` are
  // the old content's own files, discarded by the swap; every other entry is carried over.
  StagedDirectory(std::filesystem::path finalDir, std::function<bool(const std::string&)> replaced);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& finalPath() const { return final_; }
  // Puts the staged folder in place of the final one; the old content is removed.
  void commit();
  // Staging folders left beside `finalDir` by processes that no longer run, removed.
  const std::vector<std::filesystem::path>& staleRemoved() const { return stale_; }

 private:
  std::filesystem::path final_, staging_;
  std::vector<std::filesystem::path> stale_;
  std::function<bool(const std::string&)> replaced_;
  bool committed_ = false;
};

// Staging folders beside `finalDir` (and the builder's ".build-PID" folders inside it, from
// versions that built in place) whose process no longer runs: what a killed run left behind.
std::vector<std::filesystem::path> staleStagingFolders(const std::filesystem::path& finalDir);

}  // namespace nestlight
