// The command line's errors: one exit code per kind of failure, the nearest command, option or
// value for a misspelt one, US spellings read as the UK ones, and inputs of the wrong kind (a scan
// file given where an octree is read) named with the command that makes the right one.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <new>

#include "cli.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

size_t editDistance(const std::string& a, const std::string& b) {
  // Optimal string alignment: Levenshtein with swaps of neighbours ("covnert").
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<size_t>> d(n + 1, std::vector<size_t>(m + 1, 0));
  for (size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (size_t i = 1; i <= n; ++i)
    for (size_t j = 1; j <= m; ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

namespace {

std::string withoutDashes(const std::string& s) {
  const size_t k = s.find_first_not_of('-');
  return k == std::string::npos ? std::string() : s.substr(k);
}

}  // namespace

std::string nearestName(const std::string& word, const std::vector<std::string>& candidates) {
  // Within a third of the longer name's length in edits (1 to 3), dashes aside; else the one
  // candidate the word begins (at least 3 letters).
  const std::string w = withoutDashes(word);
  std::string best;
  size_t bestDistance = SIZE_MAX;
  for (const auto& c : candidates) {
    const std::string cw = withoutDashes(c);
    const size_t d = editDistance(w, cw);
    const size_t limit = std::clamp<size_t>(std::max(w.size(), cw.size()) / 3, 1, 3);
    if (d <= limit && d < bestDistance) bestDistance = d, best = c;
  }
  if (!best.empty() || w.size() < 3) return best;
  std::string only;
  int found = 0;
  for (const auto& c : candidates)
    if (withoutDashes(c).rfind(w, 0) == 0) ++found, only = c;
  return found == 1 ? only : "";
}

std::string shellQuoted(const std::string& path) {
  if (!path.empty() && path.find_first_of(" \t'\"$`\\!*?&;|<>()[]{}#~") == std::string::npos)
    return path;
  std::string q = "'";
  for (char c : path) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

namespace {

// The file in `path`'s folder whose name is nearest to the missing one (a typo): "" when none.
std::string nearFileName(const fs::path& path) {
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) return "";
  std::vector<std::string> names;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec))
    names.push_back(it->path().filename().string());
  std::sort(names.begin(), names.end());
  const std::string near = nearestName(path.filename().string(), names);
  if (near.empty()) return "";
  return path.has_parent_path() ? (path.parent_path() / near).string() : near;
}

std::string lowerCase(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The format of a scan file `nestlight convert` reads, by its name ("" for anything else).
std::string scanFormat(const fs::path& path) {
  const std::string name = lowerCase(path.filename().string());
  const std::string ext = lowerCase(path.extension().string());
  auto endsWith = [&](const char* s) {
    const std::string e = s;
    return name.size() >= e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
  };
  if (endsWith(".copc.laz")) return "COPC";
  if (ext == ".las") return "LAS";
  if (ext == ".laz") return "LAZ";
  if (ext == ".ply") return "PLY";
  if (ext == ".pcd") return "PCD";
  if (ext == ".xyz" || ext == ".pts" || ext == ".txt" || ext == ".csv") return "text (" + ext + ")";
  return "";
}

// Where `nestlight convert` would put the octree of a scan: beside it, scan.octree.
std::string octreeNameFor(const fs::path& scan) {
  std::string stem = scan.filename().string();
  const std::string lower = lowerCase(stem);
  for (const char* ext :
       {".copc.laz", ".las", ".laz", ".ply", ".pcd", ".xyz", ".pts", ".txt", ".csv"}) {
    const std::string e = ext;
    if (lower.size() > e.size() && lower.compare(lower.size() - e.size(), e.size(), e) == 0) {
      stem = stem.substr(0, stem.size() - e.size());
      break;
    }
  }
  if (stem.empty()) stem = "scan";
  return (scan.has_parent_path() ? scan.parent_path() / (stem + ".octree")
                                 : fs::path(stem + ".octree"))
      .string();
}

// Where `nestlight convert folder` would go: folder.octree beside it.
std::string folderOctreeName(const fs::path& folder) {
  fs::path n = folder.lexically_normal();
  if (n.filename().empty()) n = n.parent_path();
  if (n.empty() || n == "." || n == "..") return "scan.octree";
  return n.string() + ".octree";
}

}  // namespace

void requireExists(const std::string& path) {
  std::error_code ec;
  if (fs::exists(path, ec)) return;
  const fs::path p(path);
  std::string why = "no such file or directory";
  const std::string near = nearFileName(p);
  if (!near.empty())
    why += "; did you mean " + near + "?";
  else if (p.has_parent_path() && !fs::exists(p.parent_path(), ec))
    why += " (nor is there a folder " + p.parent_path().string() + ")";
  throw Error(path, "", why);
}

void requireOctreeFolder(const std::string& path, const std::string& command) {
  requireExists(path);
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) {
    if (fs::exists(p / "metadata.json", ec)) return;
    // A scene's folder (make-scene) or a folder of scans; anything else is left to the reader,
    // whose message also covers a conversion that did not finish.
    if (command == "render" || command == "view")
      for (const char* scene : {"scene.json"})
        if (fs::exists(p / scene, ec))
          throw Error(path, "",
                      "a scene's folder, not an octree: give its scene file, nestlight " + command +
                          " " + shellQuoted((p / scene).string()));
    for (fs::directory_iterator it(p, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec) && !scanFormat(it->path()).empty() &&
          lowerCase(it->path().extension().string()) != ".txt" &&
          lowerCase(it->path().extension().string()) != ".csv")
        throw Error(path, "",
                    "holds scan files, not an octree (no metadata.json): convert them first:\n"
                    "  nestlight convert " +
                        shellQuoted(path) + " -o " + shellQuoted(folderOctreeName(p)));
    return;
  }
  const std::string format = scanFormat(p);
  if (!format.empty())
    throw Error(path, "",
                "a " + format + " scan file, not an octree: `nestlight " + command +
                    "` reads the octree folder that `nestlight convert` builds from it:\n"
                    "  nestlight convert " +
                    shellQuoted(path) + " -o " + shellQuoted(octreeNameFor(p)));
  if (lowerCase(p.extension().string()) == ".json")
    throw Error(path, "",
                "a scene file: `nestlight " + command +
                    "` reads an octree folder (`nestlight render` and `nestlight view` take scene "
                    "files)");
  throw Error(path, "",
              "not an octree folder: `nestlight " + command +
                  "` reads the folder that `nestlight convert` builds");
}

namespace {

// US spellings in option and command names, and the UK ones the program's names use.
const std::pair<const char*, const char*> kUsToUk[] = {
    {"color", "colour"},    {"neighbor", "neighbour"}, {"izer", "iser"},
    {"ization", "isation"}, {"ized", "ised"},          {"izing", "ising"}};

std::string ukSpelling(std::string s) {
  for (const auto& [us, uk] : kUsToUk) {
    const std::string u = us, k = uk;
    for (size_t at = s.find(u); at != std::string::npos; at = s.find(u, at + k.size()))
      s.replace(at, u.size(), k);
  }
  return s;
}

CLI::App* findSubcommand(CLI::App* app, const std::string& name) {
  for (CLI::App* s : app->get_subcommands(std::function<bool(CLI::App*)>{}))
    if (s->check_name(name)) return s;
  return nullptr;
}

std::vector<std::string> subcommandNames(CLI::App* app) {
  std::vector<std::string> names;
  for (CLI::App* s : app->get_subcommands(std::function<bool(CLI::App*)>{}))
    names.push_back(s->get_name());
  return names;
}

std::vector<std::string> optionNames(CLI::App* app) {
  std::vector<std::string> names;
  for (const CLI::Option* o : app->get_options()) {
    for (const auto& l : o->get_lnames()) names.push_back("--" + l);
    for (const auto& s : o->get_snames()) names.push_back("-" + s);
  }
  return names;
}

bool hasPositionals(CLI::App* app) {
  for (const CLI::Option* o : app->get_options())
    if (o->get_positional()) return true;
  return false;
}

std::string commandPath(const CLI::App* app) {
  std::string s;
  for (; app; app = app->get_parent()) s = app->get_name() + (s.empty() ? "" : " " + s);
  return s;
}

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

// What the words of a command line name: the deepest sub-command, a word where a command was
// expected that is none, and the options the command does not have. US spellings of the
// command's options and commands are rewritten (`args`) to the UK ones on the way.
struct CommandLineReading {
  CLI::App* command = nullptr;
  std::string unknownCommand;
  std::vector<std::string> unknownOptions;
};

CommandLineReading readCommandLine(CLI::App& app, std::vector<std::string>& args) {
  CommandLineReading r;
  r.command = &app;
  for (size_t i = 0; i < args.size(); ++i) {
    std::string& word = args[i];
    if (word == "--") break;
    if (word.size() > 1 && word[0] == '-' && !(word[1] >= '0' && word[1] <= '9') &&
        word[1] != '.') {
      const size_t eq = word.find('=');
      std::string name = word.substr(0, eq);
      CLI::Option* o = r.command->get_option_no_throw(name);
      if (!o && name.rfind("--", 0) == 0) {
        const std::string uk = ukSpelling(name);
        if (uk != name && (o = r.command->get_option_no_throw(uk)) != nullptr) {
          word = uk + (eq == std::string::npos ? "" : word.substr(eq));
          name = uk;
        }
      }
      if (!o) {
        // -abc: short flags together; the first names the option.
        if (name.rfind("--", 0) != 0 && name.size() > 2 &&
            r.command->get_option_no_throw(name.substr(0, 2)))
          continue;
        r.unknownOptions.push_back(name);
        continue;
      }
      if (eq == std::string::npos && o->get_type_size_max() > 0 &&
          !(name.rfind("--", 0) != 0 && name.size() > 2))
        ++i;  // its value
      continue;
    }
    CLI::App* sub = findSubcommand(r.command, word);
    if (!sub && (sub = findSubcommand(r.command, ukSpelling(word))) != nullptr)
      word = sub->get_name();
    if (sub) {
      r.command = sub;
      continue;
    }
    if (!hasPositionals(r.command) &&
        !r.command->get_subcommands(std::function<bool(CLI::App*)>{}).empty()) {
      r.unknownCommand = word;
      break;
    }
  }
  return r;
}

// "--method: vpll not in {reference,direct,raster}": the value and the set (CLI::IsMember).
bool parseNotIn(const std::string& what, std::string* option, std::string* value,
                std::vector<std::string>* set) {
  const size_t colon = what.find(": "), notIn = what.find(" not in {");
  if (colon == std::string::npos || notIn == std::string::npos || notIn < colon) return false;
  const size_t close = what.find('}', notIn);
  if (close == std::string::npos) return false;
  *option = what.substr(0, colon);
  *value = what.substr(colon + 2, notIn - colon - 2);
  std::string items = what.substr(notIn + 9, close - notIn - 9);
  set->clear();
  for (size_t a = 0; a <= items.size();) {
    size_t b = items.find(',', a);
    if (b == std::string::npos) b = items.size();
    set->push_back(items.substr(a, b - a));
    a = b + 1;
  }
  return true;
}

// The message for a parse error, in the words of the command it is about.
std::string parseErrorMessage(const CLI::ParseError& e, const CommandLineReading& r) {
  const std::string name = e.get_name(), what = e.what();
  CLI::App* cmd = r.command;
  if (!r.unknownCommand.empty()) {
    const std::vector<std::string> names = subcommandNames(cmd);
    const std::string near = nearestName(r.unknownCommand, names);
    std::string m = "'" + r.unknownCommand + "' is not a command of " + commandPath(cmd);
    if (!near.empty()) return m + "; did you mean `" + commandPath(cmd) + " " + near + "`?";
    return m + "; the commands: " + joined(names);
  }
  if (!r.unknownOptions.empty()) {
    const std::vector<std::string> names = optionNames(cmd);
    std::string m;
    for (const auto& o : r.unknownOptions) {
      const std::string near = nearestName(o, names);
      m += (m.empty() ? "" : "; ") + std::string("unknown option ") + o;
      if (!near.empty()) m += ", did you mean " + near + "?";
    }
    return m;
  }
  if (name == "RequiredError" && what.find("ubcommand") != std::string::npos)
    return "a command is required: " + joined(subcommandNames(cmd));
  std::string option, value;
  std::vector<std::string> set;
  if (parseNotIn(what, &option, &value, &set)) {
    std::string m = option + ": '" + value + "' is not one of " + joined(set);
    const std::string near = nearestName(value, set);
    if (!near.empty()) m += "; did you mean " + near + "?";
    return m;
  }
  return what;
}

}  // namespace

int runCommandLine(CLI::App& app, int argc, char** argv, const int& exitCode) {
  std::vector<std::string> args(argv + std::min(argc, 1), argv + argc);
  CommandLineReading reading = readCommandLine(app, args);
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 pops from the back
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    const bool commands =
        !reading.command->get_subcommands(std::function<bool(CLI::App*)>{}).empty();
    std::fprintf(stderr, "%s: error: %s\nRun `%s --help` for its %s.\n",
                 commandPath(reading.command).c_str(), parseErrorMessage(e, reading).c_str(),
                 commandPath(reading.command).c_str(), commands ? "commands" : "options");
    return kExitUserError;
  } catch (const Error& e) {
    std::fprintf(stderr, "nestlight: error: %s\n", e.what());
    return kExitUserError;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "nestlight: failed: out of memory\n");
    return kExitFailure;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "nestlight: failed: %s\n", e.what());
    return kExitFailure;
  }
  return exitCode;
}

}  // namespace nestlight::cli
