// The floors of cmake/floors.txt against the sources: every #include of every C++ file of the
// checkout is compared with its folder's line, and docs/architecture.md's table of floors with the
// lines. The build enforces the same list through include directories and links
// (cmake/PzHelpers.cmake); this check also names the offending line, and covers what the build
// cannot see: includes of outside libraries (ZeroMQ, protobuf) whose headers are on every path.
#include <fnmatch.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Outside libraries with a rule; their includes are checked like folders.
const std::set<std::string> kOutside = {"protobuf", "zmq"};

struct Floors {
  std::map<std::string, std::set<std::string>> allowed;  // folder -> names on its line
  std::vector<std::string> order;                        // folders in file order
};

// Parses floors.txt; problems (syntax, unknown names, cycles) are appended to `errors`.
/// The top-level folders .gitignore keeps out of the repository ("/build*/", "/out/": what the
/// build and scripts/demo.sh write), as fnmatch patterns.
std::vector<std::string> IgnoredTopFolders(const fs::path& root) {
  std::vector<std::string> out;
  std::ifstream in(root / ".gitignore");
  for (std::string line; std::getline(in, line);)
    if (line.size() > 2 && line.front() == '/' && line.back() == '/')
      out.push_back(line.substr(1, line.size() - 2));
  return out;
}

Floors ParseFloors(const fs::path& file, std::vector<std::string>& errors) {
  Floors f;
  std::ifstream in(file);
  if (!in) {
    errors.push_back(file.string() + ": cannot be read");
    return f;
  }
  static const std::regex kLine(R"(^([A-Za-z0-9_/]+):(.*)$)");
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
    std::smatch m;
    if (!std::regex_match(line, m, kLine)) {
      errors.push_back("cmake/floors.txt:" + std::to_string(n) + ": not 'folder: names': " + line);
      continue;
    }
    const std::string folder = m[1];
    if (f.allowed.count(folder)) {
      errors.push_back("cmake/floors.txt:" + std::to_string(n) + ": second line for " + folder);
    }
    std::istringstream names(m[2].str());
    auto& set = f.allowed[folder];
    for (std::string name; names >> name;) set.insert(name);
    f.order.push_back(folder);
  }
  for (const auto& [folder, names] : f.allowed) {
    for (const auto& name : names) {
      if (!f.allowed.count(name) && !kOutside.count(name)) {
        errors.push_back("cmake/floors.txt: " + folder + " names " + name +
                         ", which is neither a folder with a line nor one of protobuf, zmq");
      }
    }
  }
  // The floors are a hierarchy: no folder reaches itself through the lines.
  std::map<std::string, int> state;  // 0 unseen, 1 on the path, 2 done
  std::vector<std::string> path;
  std::function<void(const std::string&)> visit = [&](const std::string& folder) {
    state[folder] = 1;
    path.push_back(folder);
    for (const auto& next : f.allowed[folder]) {
      if (!f.allowed.count(next)) continue;
      if (state[next] == 1) {
        std::string loop;
        for (auto it = std::find(path.begin(), path.end(), next); it != path.end(); ++it)
          loop += *it + " -> ";
        errors.push_back("cmake/floors.txt: a loop: " + loop + next);
      } else if (state[next] == 0) {
        visit(next);
      }
    }
    path.pop_back();
    state[folder] = 2;
  };
  for (const auto& folder : f.order) {
    if (state[folder] == 0) visit(folder);
  }
  return f;
}

// Floor number: 1 for a folder naming no other folder, else one above the highest it names.
int FloorOf(const Floors& f, const std::string& folder, std::map<std::string, int>& memo) {
  if (auto it = memo.find(folder); it != memo.end()) return it->second;
  memo[folder] = 1;  // a loop (reported by ParseFloors) must not recurse forever
  int floor = 1;
  for (const auto& name : f.allowed.at(folder)) {
    if (f.allowed.count(name)) floor = std::max(floor, FloorOf(f, name, memo) + 1);
  }
  return memo[folder] = floor;
}

bool IsSource(const fs::path& p) {
  const auto ext = p.extension().string();
  return ext == ".cc" || ext == ".h" || ext == ".cpp" || ext == ".hpp";
}

// The folder (a line of floors.txt) a path relative to the root belongs to: the longest line
// that is a prefix of it, or "" when none is.
std::string FolderOf(const Floors& f, const std::string& rel) {
  std::string best;
  for (const auto& [folder, names] : f.allowed) {
    if (rel.rfind(folder + "/", 0) == 0 && folder.size() > best.size()) best = folder;
  }
  return best;
}

// Every violation of the floors under `root`, one line each ("file:line: why"); empty if none.
std::vector<std::string> CheckFloors(const fs::path& root) {
  std::vector<std::string> out;
  const Floors f = ParseFloors(root / "cmake" / "floors.txt", out);
  for (const auto& folder : f.order) {
    if (!fs::is_directory(root / folder)) {
      out.push_back("cmake/floors.txt: " + folder + "/ does not exist");
    }
  }
  static const std::regex kInclude(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  const std::vector<std::string> ignored_top = IgnoredTopFolders(root);
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator();
       ++it) {
    const fs::path& p = it->path();
    if (it->is_directory()) {
      // Hidden folders, build trees (anything configured by CMake) and the top-level folders
      // .gitignore keeps out (scripts/demo.sh writes a C header into out/) are not sources.
      const std::string name = p.filename().string();
      const bool ignored =
          it.depth() == 0 &&
          std::any_of(ignored_top.begin(), ignored_top.end(), [&](const std::string& g) {
            return ::fnmatch(g.c_str(), name.c_str(), 0) == 0;
          });
      if (name[0] == '.' || fs::exists(p / "CMakeCache.txt") || ignored) {
        it.disable_recursion_pending();
      }
      continue;
    }
    if (!it->is_regular_file() || !IsSource(p)) continue;
    const std::string rel = fs::relative(p, root).generic_string();
    const std::string folder = FolderOf(f, rel);
    if (folder.empty()) {
      out.push_back(rel + ": its folder has no line in cmake/floors.txt");
      continue;
    }
    const auto& allowed = f.allowed.at(folder);
    std::ifstream in(p);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      std::smatch m;
      if (!std::regex_search(line, m, kInclude)) continue;
      const bool quoted = m[1] == "\"";
      const std::string inc = m[2];
      std::string name;  // the folder or outside library the include reaches; "" = no rule
      if (!quoted) {
        if (inc == "zmq.hpp" || inc == "zmq.h" || inc == "zmq_addon.hpp") name = "zmq";
        if (inc.rfind("google/protobuf/", 0) == 0) name = "protobuf";
        if (name.empty()) continue;
      } else if (inc.size() > 5 && inc.compare(inc.size() - 5, 5, ".pb.h") == 0) {
        name = "proto";  // generated from proto/*.proto
      } else if (fs::exists(p.parent_path() / inc)) {
        const fs::path target = fs::weakly_canonical(p.parent_path() / inc);
        name = FolderOf(f, fs::relative(target, fs::weakly_canonical(root)).generic_string());
      } else if (const auto slash = inc.find('/'); slash != std::string::npos) {
        name = FolderOf(f, inc);
        if (name.empty()) name = inc.substr(0, slash);
      } else {
        // A header generated into the folder's build directory: its CMakeLists.txt names it.
        std::ifstream cmake(root / folder / "CMakeLists.txt");
        std::stringstream text;
        text << cmake.rdbuf();
        if (text.str().find(inc) != std::string::npos) continue;
        out.push_back(rel + ":" + std::to_string(n) + ": #include \"" + inc +
                      "\" is neither beside the file, nor under a folder, nor generated by " +
                      folder + "/CMakeLists.txt");
        continue;
      }
      if (name == folder || allowed.count(name)) continue;
      if (name == "tests/testing" && folder.rfind("tests/", 0) == 0) continue;  // test helpers
      std::string line_of;
      for (const auto& a : allowed) line_of += " " + a;
      out.push_back(rel + ":" + std::to_string(n) + ": #include " +
                    std::string(1, line[m.position(1)]) + inc + (quoted ? "\"" : ">") + ": " +
                    folder + "/ may not include " + name + " (cmake/floors.txt: " + folder + ":" +
                    line_of + ")");
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string ReadFile(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool HasWord(const std::string& text, const std::string& word) {
  return std::regex_search(text, std::regex("(^|[^A-Za-z0-9_])" + word + "($|[^A-Za-z0-9_])"));
}

// Every .cc of the checkout is built: its folder's CMakeLists.txt names it (its file name or
// stem; a test tests/<folder>/<name>_test.cc by <name> in tests/CMakeLists.txt's
// PZ_TESTS_<folder>). The CMakeLists list their sources, so a file they do not name would silently
// not be compiled.
std::vector<std::string> UnlistedSources(const fs::path& root) {
  std::vector<std::string> out;
  std::vector<std::string> errors;
  const Floors f = ParseFloors(root / "cmake" / "floors.txt", errors);
  const std::string tests_cmake = ReadFile(root / "tests" / "CMakeLists.txt");
  for (const auto& folder : f.order) {
    if (folder == "tests/testing" || !fs::is_directory(root / folder)) continue;
    for (const auto& e : fs::directory_iterator(root / folder)) {
      if (e.path().extension() != ".cc") continue;
      const std::string name = e.path().filename().string();
      const std::string stem = e.path().stem().string();
      bool listed;
      if (folder.rfind("tests/", 0) == 0) {
        const std::string group = folder.substr(6);
        std::smatch m;
        const std::regex set_re("set\\(PZ_TESTS_" + group + "\\s([^)]*)\\)");
        listed = std::regex_search(tests_cmake, m, set_re) && stem.size() > 5 &&
                 stem.compare(stem.size() - 5, 5, "_test") == 0 &&
                 HasWord(m[1].str(), stem.substr(0, stem.size() - 5));
      } else {
        const std::string cmake = ReadFile(root / folder / "CMakeLists.txt");
        listed = cmake.find(name) != std::string::npos || HasWord(cmake, stem);
      }
      if (!listed) {
        out.push_back(
            folder + "/" + name + ": not named in " +
            (folder.rfind("tests/", 0) == 0 ? "tests/CMakeLists.txt" : folder + "/CMakeLists.txt"));
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Whether the namespace block opened at `open` (the offset of "namespace") only forward-declares
// (class/struct/enum names, comments): a file may name another folder's types that way.
bool OnlyForwardDeclares(const std::string& text, size_t open) {
  const size_t body = text.find('{', open);
  const size_t end = text.find("\n}", body);
  std::istringstream lines(text.substr(body + 1, end - body - 1));
  static const std::regex kForward(
      R"(^\s*((class|struct|enum class|enum)\s+\w+(\s*:\s*[\w:]+)?;\s*(//.*)?|//.*|)$)");
  for (std::string line; std::getline(lines, line);)
    if (!std::regex_match(line, kForward)) return false;
  return true;
}

// Namespaces follow folders: a source of the product's folder F opens pz::F (or a namespace
// inside it, or an anonymous one); another folder's namespace only to forward-declare its types.
// model/, the floor everything stands on, also holds the project's base vocabulary in pz
// (model/status.h, model/format.h), and model/kernels/ the C step kernels' C++ names in pz::pzk
// (their C prefix pzk_). One line a stray block: "file:line: why".
std::vector<std::string> NamespacesAgainstFolders(const fs::path& root) {
  std::vector<std::string> out;
  std::vector<std::string> errors;
  const Floors f = ParseFloors(root / "cmake" / "floors.txt", errors);
  static const std::regex kOpen(R"((^|\n)namespace ([A-Za-z_][\w:]*) \{)");
  for (const auto& folder : f.order) {
    if (folder.rfind("tests", 0) == 0 || folder == "bench" || folder == "fuzz" ||
        !fs::is_directory(root / folder))
      continue;
    for (const auto& e : fs::recursive_directory_iterator(root / folder)) {
      if (!IsSource(e.path())) continue;
      const std::string text = ReadFile(e.path());
      for (auto it = std::sregex_iterator(text.begin(), text.end(), kOpen);
           it != std::sregex_iterator(); ++it) {
        const std::string ns = (*it)[2];
        const size_t at = it->position(0) + it->length(1);
        const bool project = ns == "pz" || ns.rfind("pz::", 0) == 0;
        const bool own =
            !project || ns == "pz::" + folder || ns.rfind("pz::" + folder + "::", 0) == 0 ||
            (folder == "model" && ns == "pz") ||
            (ns == "pz::pzk" &&
             fs::relative(e.path(), root).generic_string().rfind("model/kernels/", 0) == 0);
        if (own || OnlyForwardDeclares(text, at)) continue;
        const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
        out.push_back(fs::relative(e.path(), root).generic_string() + ":" + std::to_string(line) +
                      ": namespace " + ns + " in folder " + folder + "/ (pz::" + folder + ")");
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string Join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

void Write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

// A scratch tree with this checkout's floors.txt and an empty folder for each of its lines.
class ScratchTree : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("pz_floors_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "cmake");
    fs::copy_file(fs::path(PIEZOID_SOURCE_DIR) / "cmake" / "floors.txt",
                  root_ / "cmake" / "floors.txt");
    std::vector<std::string> errors;
    for (const auto& folder : ParseFloors(root_ / "cmake" / "floors.txt", errors).order) {
      fs::create_directories(root_ / folder);
    }
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

}  // namespace

TEST(Floors, TheSourcesKeepToTheFloors) {
  const auto violations = CheckFloors(PIEZOID_SOURCE_DIR);
  EXPECT_TRUE(violations.empty()) << Join(violations);
}

TEST(Floors, NamespacesFollowFolders) {
  const auto stray = NamespacesAgainstFolders(PIEZOID_SOURCE_DIR);
  EXPECT_TRUE(stray.empty()) << Join(stray);
}

TEST_F(ScratchTree, ANamespaceOfAnotherFolderIsCaught) {
  Write(root_ / "io" / "a.h",
        "namespace pz::proto {\nclass Fit;  // forward\n}  // namespace pz::proto\n"
        "namespace pz::io {\nint A();\n}  // namespace pz::io\n");
  Write(root_ / "diagnose" / "b.cc",
        "namespace pz::diagnose::detail {\nint B();\n}\n"
        "namespace {\nint C();\n}\n"
        "namespace pz::records {\nint D();\n}  // namespace pz::records\n");
  Write(root_ / "model" / "s.h", "namespace pz {\nenum class StatusCode : int { kOk };\n}\n");
  Write(root_ / "opt" / "c.h", "namespace pz {\nint E();\n}\n");
  const auto v = NamespacesAgainstFolders(root_);
  ASSERT_EQ(v.size(), 2u) << Join(v);
  EXPECT_EQ(v[0], "diagnose/b.cc:7: namespace pz::records in folder diagnose/ (pz::diagnose)");
  EXPECT_EQ(v[1], "opt/c.h:1: namespace pz in folder opt/ (pz::opt)");
}

TEST(Floors, EverySourceIsListedInItsCMakeLists) {
  const auto unlisted = UnlistedSources(PIEZOID_SOURCE_DIR);
  EXPECT_TRUE(unlisted.empty()) << Join(unlisted);
}

TEST_F(ScratchTree, AnUnlistedSourceIsCaught) {
  Write(root_ / "opt" / "CMakeLists.txt", "pz_cc_library(NAME opt SRCS ga.cc)\n");
  Write(root_ / "opt" / "ga.cc", "");
  Write(root_ / "opt" / "ga_extra.cc", "");
  Write(root_ / "tests" / "CMakeLists.txt", "set(PZ_TESTS_opt ga\n    param_search)\n");
  Write(root_ / "tests" / "opt" / "param_search_test.cc", "");
  Write(root_ / "tests" / "opt" / "search_test.cc", "");
  const auto v = UnlistedSources(root_);
  ASSERT_EQ(v.size(), 2u) << Join(v);
  EXPECT_EQ(v[0], "opt/ga_extra.cc: not named in opt/CMakeLists.txt");
  EXPECT_EQ(v[1], "tests/opt/search_test.cc: not named in tests/CMakeLists.txt");
}

TEST_F(ScratchTree, APlantedUpwardIncludeIsCaught) {
  Write(root_ / "opt" / "legal.cc",
        "#include \"opt/ga.h\"\n#include \"model/signal.h\"\n#include <vector>\n");
  ASSERT_TRUE(CheckFloors(root_).empty()) << Join(CheckFloors(root_));

  Write(root_ / "model" / "planted.h", "#pragma once\n#include \"opt/ga.h\"\n");
  Write(root_ / "opt" / "planted.cc",
        "#include <zmq.hpp>\n#include \"wire.pb.h\"\n"
        "#include <google/protobuf/message.h>\n");
  Write(root_ / "worker" / "planted.cc", "#include \"master/broker.h\"\n");
  Write(root_ / "client" / "planted.cc",
        "#include \"worker/worker.h\"\n\n#include \"master/job_store.h\"\n");
  const auto v = CheckFloors(root_);
  ASSERT_EQ(v.size(), 7u) << Join(v);
  EXPECT_NE(
      v[0].find(
          "client/planted.cc:1: #include \"worker/worker.h\": client/ may not include worker"),
      std::string::npos)
      << v[0];
  EXPECT_NE(v[1].find("client/planted.cc:3: #include \"master/job_store.h\""), std::string::npos)
      << v[1];
  EXPECT_NE(v[2].find("model/planted.h:2: #include \"opt/ga.h\": model/ may not include opt"),
            std::string::npos)
      << v[2];
  EXPECT_NE(v[3].find("opt/planted.cc:1: #include <zmq.hpp>: opt/ may not include zmq"),
            std::string::npos)
      << v[3];
  EXPECT_NE(v[4].find("opt/planted.cc:2: #include \"wire.pb.h\": opt/ may not include proto"),
            std::string::npos)
      << v[4];
  EXPECT_NE(
      v[5].find(
          "opt/planted.cc:3: #include <google/protobuf/message.h>: opt/ may not include protobuf"),
      std::string::npos)
      << v[5];
  EXPECT_NE(
      v[6].find(
          "worker/planted.cc:1: #include \"master/broker.h\": worker/ may not include master"),
      std::string::npos)
      << v[6];
}

TEST_F(ScratchTree, AFolderWithoutALineAndAnUnknownIncludeAreCaught) {
  Write(root_ / "newfloor" / "x.cc", "int x;\n");
  Write(root_ / "model" / "y.cc",
        "#include \"nowhere.h\"\n#include \"tests/testing/expect_error.h\"\n");
  Write(root_ / "tests" / "model" / "y_test.cc", "#include \"tests/testing/expect_error.h\"\n");
  const auto v = CheckFloors(root_);
  ASSERT_EQ(v.size(), 3u) << Join(v);
  EXPECT_NE(v[0].find("model/y.cc:1: #include \"nowhere.h\" is neither beside"), std::string::npos)
      << v[0];
  EXPECT_NE(
      v[1].find("model/y.cc:2: #include \"tests/testing/expect_error.h\": model/ may not include "
                "tests/testing"),
      std::string::npos)
      << v[1];
  EXPECT_EQ(v[2], "newfloor/x.cc: its folder has no line in cmake/floors.txt");
}

TEST_F(ScratchTree, ALoopInTheListIsRefused) {
  Write(root_ / "cmake" / "floors.txt", "model: opt\nopt: model\nio: model nosuch\n");
  std::vector<std::string> errors;
  ParseFloors(root_ / "cmake" / "floors.txt", errors);
  ASSERT_EQ(errors.size(), 2u) << Join(errors);
  EXPECT_NE(Join(errors).find("io names nosuch"), std::string::npos) << Join(errors);
  EXPECT_NE(Join(errors).find("a loop: model -> opt -> model"), std::string::npos) << Join(errors);
}

// docs/architecture.md's table of floors: one row per library folder, its floor and its line.
TEST(Floors, TheArchitectureTableIsTheList) {
  std::vector<std::string> errors;
  const Floors f = ParseFloors(fs::path(PIEZOID_SOURCE_DIR) / "cmake" / "floors.txt", errors);
  ASSERT_TRUE(errors.empty()) << Join(errors);
  std::ifstream in(fs::path(PIEZOID_SOURCE_DIR) / "docs" / "architecture.md");
  ASSERT_TRUE(in) << "docs/architecture.md";
  // | floor | `folder/` | what | may include |
  static const std::regex kRow(R"(^\| (\d+) \| `([a-z]+)/` \|.*\| ([^|]*) \|\s*$)");
  std::map<std::string, int> memo;
  std::set<std::string> rows;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::smatch m;
    if (!std::regex_match(line, m, kRow)) continue;
    const std::string folder = m[2];
    const std::string where = "docs/architecture.md:" + std::to_string(n) + " (" + folder + "/)";
    rows.insert(folder);
    ASSERT_TRUE(f.allowed.count(folder)) << where << ": no line in cmake/floors.txt";
    EXPECT_EQ(std::stoi(m[1]), FloorOf(f, folder, memo)) << where << ": floor";
    std::set<std::string> listed;
    std::istringstream names(std::regex_replace(m[3].str(), std::regex("[`,]"), " "));
    for (std::string name; names >> name;) {
      if (name != "—") listed.insert(name);
    }
    EXPECT_EQ(listed, f.allowed.at(folder))
        << where << ": the names on its line of cmake/floors.txt";
  }
  for (const auto& folder : f.order) {
    if (folder.find('/') == std::string::npos && folder != "bench" && folder != "fuzz") {
      EXPECT_TRUE(rows.count(folder)) << "docs/architecture.md has no row for " << folder << "/";
    }
  }
}
