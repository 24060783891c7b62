// Every repository path named in README.md, docs/*.md and the sources' comments exists. A path is
// a token like
// `opt/param_search.h`, `dashboard/page/`, `tests/deploy/*_test.sh` or `reports/plots.{h,cc}`
// whose first part is an entry of the repository's top folder (or, starting with ../, one that
// resolves inside the repository from the document's folder); `*` must match at least one entry
// and `{a,b}` names each alternative.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// `pattern` with its first {a,b,...} expanded, recursively.
std::vector<std::string> ExpandBraces(const std::string& pattern) {
  const auto open = pattern.find('{');
  const auto close = pattern.find('}', open);
  if (open == std::string::npos || close == std::string::npos) return {pattern};
  std::vector<std::string> out;
  const std::string alts = pattern.substr(open + 1, close - open - 1);
  for (size_t start = 0;;) {
    const auto comma = alts.find(',', start);
    const std::string alt =
        alts.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    for (auto& s : ExpandBraces(pattern.substr(0, open) + alt + pattern.substr(close + 1))) {
      out.push_back(std::move(s));
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// Whether `name` matches `glob` ('*' = any run of characters).
bool Matches(const std::string& glob, const std::string& name) {
  std::string re;
  for (char c : glob)
    re += c == '*' ? std::string(".*")
                   : std::regex_replace(std::string(1, c), std::regex(R"([.^$|()\[\]{}+?\\])"),
                                        R"(\$&)");
  return std::regex_match(name, std::regex(re));
}

// Whether `rel` (relative to root, '/'-separated, may hold '*' in its parts) names something.
bool Exists(const fs::path& root, const std::string& rel) {
  std::vector<fs::path> here = {root};
  size_t start = 0;
  while (start < rel.size()) {
    const auto slash = rel.find('/', start);
    const std::string part =
        rel.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    start = slash == std::string::npos ? rel.size() : slash + 1;
    if (part.empty()) continue;
    std::vector<fs::path> next;
    for (const auto& dir : here) {
      if (part.find('*') == std::string::npos) {
        if (fs::exists(dir / part)) next.push_back(dir / part);
      } else if (fs::is_directory(dir)) {
        for (const auto& e : fs::directory_iterator(dir)) {
          if (Matches(part, e.path().filename().string())) next.push_back(e.path());
        }
      }
    }
    here = std::move(next);
    if (here.empty()) return false;
  }
  return true;
}

// The comment of a source line: after "//" or a block comment's "/*" or leading "*" (C, C++,
// proto), after "#" (CMake, shell, Python); "" for a line without one.
std::string CommentOf(const std::string& line, bool hash) {
  if (hash) {
    const auto at = line.find('#');
    return at == std::string::npos || (at > 0 && line[at - 1] != ' ') ? "" : line.substr(at + 1);
  }
  if (const auto at = line.find("//"); at != std::string::npos) return line.substr(at + 2);
  if (const auto at = line.find("/*"); at != std::string::npos) return line.substr(at + 2);
  const auto first = line.find_first_not_of(' ');
  return first != std::string::npos && line[first] == '*' ? line.substr(first + 1) : "";
}

// The repository paths named in `doc` that do not exist, as "doc:line: path". A source file
// (`comments`) is read for its comments only.
std::vector<std::string> MissingPaths(const fs::path& root, const fs::path& doc,
                                      bool comments = false) {
  std::set<std::string> top;
  for (const auto& e : fs::directory_iterator(root)) {
    const auto name = e.path().filename().string();
    if (name[0] != '.' && !fs::exists(e.path() / "CMakeCache.txt")) top.insert(name);
  }
  const std::string doc_dir = fs::relative(doc.parent_path(), root).generic_string();
  // A token: optional ../ steps, then parts of path characters separated by '/', not preceded by
  // a character that would make it part of a URL or a longer word.
  static const std::regex kToken(
      R"((^|[^A-Za-z0-9_./:~@$<-])((?:\.\./)*[A-Za-z0-9_.-]+(?:/[A-Za-z0-9_.*@{},-]+)+/?))");
  std::vector<std::string> out;
  std::ifstream in(doc);
  std::string line;
  const std::string ext = doc.extension().string();
  const bool hash = ext == ".txt" || ext == ".sh" || ext == ".py" || ext == ".cmake" ||
                    doc.filename() == "CMakeLists.txt";
  for (int n = 1; std::getline(in, line); ++n) {
    if (comments) line = CommentOf(line, hash);
    for (auto it = std::sregex_iterator(line.begin(), line.end(), kToken);
         it != std::sregex_iterator(); ++it) {
      std::string token = (*it)[2];
      while (!token.empty() && (token.back() == '.' || token.back() == ',')) token.pop_back();
      std::string rel = token;
      if (rel.rfind("../", 0) == 0) {
        // Relative to the document's folder; a path leaving the repository is not one of its paths.
        fs::path p = fs::path(doc_dir) / rel;
        rel = p.lexically_normal().generic_string();
        if (rel.rfind("..", 0) == 0) continue;
      }
      if (!top.count(rel.substr(0, rel.find('/')))) continue;
      for (const auto& alt : ExpandBraces(rel)) {
        if (!Exists(root, alt)) {
          out.push_back(fs::relative(doc, root).generic_string() + ":" + std::to_string(n) + ": " +
                        token + (alt == rel ? "" : " (" + alt + ")"));
        }
      }
    }
  }
  return out;
}

std::vector<fs::path> Docs(const fs::path& root) {
  std::vector<fs::path> docs = {root / "README.md"};
  for (const auto& e : fs::directory_iterator(root / "docs")) {
    if (e.path().extension() == ".md") docs.push_back(e.path());
  }
  return docs;
}

// The sources whose comments are read: the C, C++, proto, CMake, shell and Python files git
// would track (every folder of the top but build trees and dot-folders; tests/data holds data).
std::vector<fs::path> Sources(const fs::path& root) {
  std::vector<fs::path> out;
  static const std::set<std::string> kExt = {".cc",  ".h",     ".c",  ".proto",
                                             ".txt", ".cmake", ".sh", ".py"};
  for (const auto& top : fs::directory_iterator(root)) {
    const auto name = top.path().filename().string();
    if (!top.is_directory() || name[0] == '.' || fs::exists(top.path() / "CMakeCache.txt") ||
        name == "out")
      continue;
    for (auto it = fs::recursive_directory_iterator(top.path()); it != fs::end(it); ++it) {
      const auto fname = it->path().filename().string();
      // tests/layout's fixtures name stale paths on purpose.
      if (it->is_directory() && (fname == "data" || fname[0] == '.' || fname == "node_modules" ||
                                 it->path() == root / "tests" / "layout")) {
        it.disable_recursion_pending();
      } else if (it->is_regular_file() && kExt.count(it->path().extension().string()) &&
                 fname.find(".pb.") == std::string::npos) {
        out.push_back(it->path());
      }
    }
  }
  out.push_back(root / "CMakeLists.txt");
  return out;
}

std::string Join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

TEST(DocPaths, EveryRepositoryPathInTheDocsExists) {
  const fs::path root = PIEZOID_SOURCE_DIR;
  std::vector<std::string> missing;
  size_t docs = 0;
  for (const auto& doc : Docs(root)) {
    ++docs;
    for (auto& m : MissingPaths(root, doc)) missing.push_back(std::move(m));
  }
  EXPECT_GE(docs, 2u);
  EXPECT_TRUE(missing.empty()) << Join(missing);
}

TEST(DocPaths, EveryRepositoryPathInTheSourcesCommentsExists) {
  const fs::path root = PIEZOID_SOURCE_DIR;
  std::vector<std::string> missing;
  size_t sources = 0;
  for (const auto& source : Sources(root)) {
    ++sources;
    for (auto& m : MissingPaths(root, source, true)) missing.push_back(std::move(m));
  }
  EXPECT_GE(sources, 100u);
  EXPECT_TRUE(missing.empty()) << Join(missing);
}

// The check on a scratch repository: stale paths are named with their line, the rest pass.
TEST(DocPaths, AStalePathIsCaught) {
  const fs::path root = fs::temp_directory_path() / ("pz_doc_paths_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "docs");
  fs::create_directories(root / "opt");
  fs::create_directories(root / "master");
  fs::create_directories(root / "tests" / "deploy");
  std::ofstream(root / "opt" / "ga.h") << "";
  std::ofstream(root / "opt" / "ga.cc") << "";
  std::ofstream(root / "tests" / "deploy" / "netns_test.sh") << "";
  std::ofstream(root / "docs" / "a.md")
      << "The GA: `opt/ga.h`, `opt/ga.{h,cc}` and [the page](../opt/ga.h), "
         "tests/deploy/*_test.sh.\n"
         "See https://example.org/opt/nothing.h, state/jobs/<id>/spec.pb and ../../outside/x.h.\n"
         "Moved: `master/ga.h`, opt/{ga,gone}.h, tests/deploy/*_validate.sh, ../opt/old.h.\n";
  const auto missing = MissingPaths(root, root / "docs" / "a.md");
  fs::remove_all(root);
  ASSERT_EQ(missing.size(), 4u) << Join(missing);
  EXPECT_EQ(missing[0], "docs/a.md:3: master/ga.h");
  EXPECT_EQ(missing[1], "docs/a.md:3: opt/{ga,gone}.h (opt/gone.h)");
  EXPECT_EQ(missing[2], "docs/a.md:3: tests/deploy/*_validate.sh");
  EXPECT_EQ(missing[3], "docs/a.md:3: ../opt/old.h");
}

// In a source only the comments are read: a path in code (a string, an include of a generated
// header) is not a claim about the tree.
TEST(DocPaths, AStalePathInASourceCommentIsCaught) {
  const fs::path root = fs::temp_directory_path() / ("pz_src_paths_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "opt");
  std::ofstream(root / "opt" / "ga.h") << "";
  std::ofstream(root / "opt" / "ga.cc")
      << "#include \"opt/ga.h\"\n"
         "const char* kPath = \"opt/not_a_claim.h\";  // the GA of opt/ga.h\n"
         "/* moved to opt/gone.h\n"
         " * and opt/ga.h */\n";
  std::ofstream(root / "opt" / "CMakeLists.txt") << "# opt/ga.cc and opt/old.cc\nSRCS opt/x.cc\n";
  auto missing = MissingPaths(root, root / "opt" / "ga.cc", true);
  const auto cmake = MissingPaths(root, root / "opt" / "CMakeLists.txt", true);
  missing.insert(missing.end(), cmake.begin(), cmake.end());
  fs::remove_all(root);
  ASSERT_EQ(missing.size(), 2u) << Join(missing);
  EXPECT_EQ(missing[0], "opt/ga.cc:3: opt/gone.h");
  EXPECT_EQ(missing[1], "opt/CMakeLists.txt:1: opt/old.cc");
}

// A merge's conflict markers left in a committed file (a doc merges without a build error).
TEST(DocPaths, NoMergeConflictMarkers) {
  const fs::path root = PIEZOID_SOURCE_DIR;
  std::vector<fs::path> files = Docs(root);
  for (auto& s : Sources(root)) files.push_back(std::move(s));
  const std::string ours = std::string(7, '<') + " ", theirs = std::string(7, '>') + " ";
  std::vector<std::string> found;
  for (const auto& file : files) {
    std::ifstream in(file);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (line.rfind(ours, 0) == 0 || line.rfind(theirs, 0) == 0)
        found.push_back(fs::relative(file, root).generic_string() + ":" + std::to_string(n));
    }
  }
  EXPECT_TRUE(found.empty()) << Join(found);
}
