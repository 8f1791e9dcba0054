// The engine's house rules, read from its sources (issue 52): layers include only downwards, and
// each pass's kernels live in the one kernel file named like it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

const fs::path kSource = SHADOW_SOURCE_DIR;
const fs::path kEngine = kSource / "server" / "engine";

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The engine's layers, lowest first (docs/architecture.md, "Layers"): a file may include its
// own layer and those below it, never one above.
int layer_of(const fs::path& file) {
  static const std::map<std::string, int> kLayers = {
      {"device_types.hpp", 0}, {"cl", 1},  {"light", 1},      {"plan", 2},      {"choose", 3},
      {"passes", 4},           {"run", 5}, {"engine.hpp", 6}, {"engine.cpp", 6}};
  const std::string top = fs::relative(file, kEngine).begin()->string();
  const auto it = kLayers.find(top);
  return it == kLayers.end() ? -1 : it->second;
}

std::vector<fs::path> engine_files() {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(kEngine))
    if (e.path().extension() == ".hpp" || e.path().extension() == ".cpp") files.push_back(e.path());
  return files;
}

TEST(Layers, EveryEngineFileHasALayer) {
  for (const fs::path& f : engine_files()) EXPECT_GE(layer_of(f), 0) << f;
}

TEST(Layers, NoFileIncludesALayerAboveItsOwn) {
  const std::regex include(R"re(#include "engine/([^"]+)")re");
  size_t includes = 0;
  for (const fs::path& f : engine_files()) {
    const std::string text = read(f);
    for (std::sregex_iterator m(text.begin(), text.end(), include), end; m != end; ++m) {
      const fs::path target = kEngine / (*m)[1].str();
      ++includes;
      EXPECT_LE(layer_of(target), layer_of(f))
          << fs::relative(f, kSource) << " includes " << (*m)[1] << ", a higher layer";
    }
  }
  EXPECT_GT(includes, 100u);  // the sources were found and read
}

// kernels/X.cl defines kernels, and passes/X.cpp or .hpp launches them; no other host file
// names X.cl. Files without kernels are includes shared by several passes (prelude.cl).
TEST(KernelFiles, EveryPassHasOneKernelFileOfItsName) {
  std::set<std::string> with_kernels;
  for (const auto& e : fs::directory_iterator(kSource / "kernels")) {
    if (e.path().extension() != ".cl") continue;
    if (std::regex_search(read(e.path()), std::regex(R"((^|[^a-z_])(__)?kernel\s+void\b)")))
      with_kernels.insert(e.path().stem().string());
  }
  EXPECT_GT(with_kernels.size(), 15u);
  for (const std::string& stem : with_kernels)
    EXPECT_TRUE(fs::exists(kEngine / "passes" / (stem + ".cpp")) ||
                fs::exists(kEngine / "passes" / (stem + ".hpp")))
        << "kernels/" << stem << ".cl has no host file passes/" << stem << ".cpp";
  const std::regex named(R"re(\.kernel\(\s*"([a-z_0-9]+)\.cl")re");
  std::set<std::string> launched;
  for (const fs::path& f : engine_files()) {
    const std::string text = read(f);
    for (std::sregex_iterator m(text.begin(), text.end(), named), end; m != end; ++m) {
      launched.insert((*m)[1]);
      EXPECT_EQ(f.parent_path().filename(), "passes") << fs::relative(f, kSource);
      EXPECT_EQ(f.stem().string(), (*m)[1].str())
          << fs::relative(f, kSource) << " builds " << (*m)[1] << ".cl, another pass's file";
    }
  }
  EXPECT_EQ(launched, with_kernels);  // every kernel file is launched, and only those
}

// Every kernel of kernels/X.cl is named in passes/X.cpp or .hpp: the pass that launches it.
TEST(KernelFiles, EveryKernelIsNamedByItsFilesPass) {
  const std::regex defined(R"re((?:^|[^a-z_])(?:__)?kernel\s+void\s+([a-z_0-9]+)\s*\()re");
  size_t kernels = 0;
  for (const auto& e : fs::directory_iterator(kSource / "kernels")) {
    if (e.path().extension() != ".cl") continue;
    const std::string text = read(e.path()), stem = e.path().stem().string();
    const std::string host = read(kEngine / "passes" / (stem + ".cpp")) +
                             read(kEngine / "passes" / (stem + ".hpp"));
    for (std::sregex_iterator m(text.begin(), text.end(), defined), end; m != end; ++m, ++kernels)
      EXPECT_NE(host.find('"' + (*m)[1].str() + '"'), std::string::npos)
          << "kernels/" << stem << ".cl's " << (*m)[1] << " is not named by passes/" << stem
          << ".cpp";
  }
  EXPECT_GT(kernels, 60u);
}

// What a filter is lives in one table (engine/plan/filter.*): nothing else switches on or
// compares FilterKind.
TEST(Tables, OnlyTheFilterTableBranchesOnTheFilter) {
  const std::regex branch(R"re(case FilterKind::|[!=]=\s*FilterKind::|FilterKind::k\w+\s*[!=]=)re");
  for (const fs::path& f : engine_files()) {
    if (fs::relative(f, kEngine) == fs::path("plan/filter.cpp")) continue;
    const std::string text = read(f);
    EXPECT_FALSE(std::regex_search(text, branch)) << fs::relative(f, kSource);
  }
}

}  // namespace
