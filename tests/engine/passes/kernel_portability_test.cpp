// Kernels that any conforming OpenCL C 1.2 compiler builds (issue 41): no compiler builtins
// outside the spec unless guarded by CLANG_CPU_BUILTINS (set only for PoCL's CPU devices), no
// functions whose rounding each device chooses, and every program the engine's start-up builds
// compiling without a warning, as PoCL and as any other compiler sees it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/engine.hpp"

namespace shadow {
namespace {

// The source with comments blanked (line breaks kept, so line numbers hold).
std::string without_comments(const std::string& s) {
  std::string out = s;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out.compare(i, 2, "//") == 0) {
      while (i < out.size() && out[i] != '\n') out[i++] = ' ';
    } else if (out.compare(i, 2, "/*") == 0) {
      const size_t end = std::min(out.find("*/", i + 2), out.size() - 2) + 2;
      for (; i < end; ++i)
        if (out[i] != '\n') out[i] = ' ';
      --i;
    }
  }
  return out;
}

// "line N: what" for each construct of `source` that another conforming compiler may refuse or
// round differently:
// - a clang builtin (__builtin_*) outside an #ifdef CLANG_CPU_BUILTINS branch;
// - native_* and half_* math, mad(): their precision is the implementation's;
// - FP_CONTRACT ON: contraction rounds differently where a compiler fuses.
std::vector<std::string> portability_problems(const std::string& source) {
  static const std::regex guard_open(
      R"(^\s*#\s*(ifdef\s+CLANG_CPU_BUILTINS\b|if\s+defined\s*\(?\s*CLANG_CPU_BUILTINS\b))");
  static const std::regex other_open(R"(^\s*#\s*if)");
  static const std::regex branch(R"(^\s*#\s*(else|elif)\b)");
  static const std::regex close(R"(^\s*#\s*endif\b)");
  static const std::regex builtin(R"(\b__builtin_\w+)");
  static const std::regex imprecise(
      R"(\b(native_\w+|mad|half_(cos|divide|exp|exp2|exp10|log|log2|log10|powr|recip|rsqrt|)"
      R"(sin|sqrt|tan))\s*\()");
  static const std::regex contract_on(R"(FP_CONTRACT\s+(ON|DEFAULT))");
  std::vector<std::string> problems;
  std::vector<bool> guarded;  // per open conditional: inside CLANG_CPU_BUILTINS' own branch
  std::istringstream lines(without_comments(source));
  std::string line;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (std::regex_search(line, guard_open)) {
      guarded.push_back(true);
    } else if (std::regex_search(line, other_open)) {
      guarded.push_back(false);
    } else if (std::regex_search(line, branch)) {
      if (!guarded.empty()) guarded.back() = false;
    } else if (std::regex_search(line, close)) {
      if (!guarded.empty()) guarded.pop_back();
    }
    const bool in_guard = std::find(guarded.begin(), guarded.end(), true) != guarded.end();
    const auto each = [&](const std::regex& r, const std::string& why) {
      for (auto m = std::sregex_iterator(line.begin(), line.end(), r); m != std::sregex_iterator();
           ++m)
        problems.push_back("line " + std::to_string(n) + ": " + m->str() + why);
    };
    if (!in_guard) each(builtin, " outside #ifdef CLANG_CPU_BUILTINS");
    each(imprecise, " (the device chooses its rounding)");
    each(contract_on, "");
  }
  return problems;
}

// $SHADOW_KERNEL_DIR (to check another tree's kernels), else this tree's kernels/.
std::filesystem::path kernel_dir() {
  const char* dir = std::getenv("SHADOW_KERNEL_DIR");
  return dir ? dir : SHADOW_SOURCE_KERNEL_DIR;
}

std::vector<std::filesystem::path> kernel_files() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(kernel_dir()))
    if (entry.path().extension() == ".cl") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Sets an environment variable for the scope's lifetime.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(KernelPortability, TheCheckFindsTheBuiltinNvidiaRefused) {
  // kernels/sat.cl (now summed_area.cl) before issue 41: NVIDIA's compiler stopped on this line.
  const std::string unguarded =
      "for (uint e = 0; e < nv; e += 8) {\n"
      "  __builtin_prefetch(in + e + 2 * (size_t)width);\n"
      "}\n";
  const std::vector<std::string> found = portability_problems(unguarded);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0], "line 2: __builtin_prefetch outside #ifdef CLANG_CPU_BUILTINS");

  EXPECT_TRUE(portability_problems("#ifdef CLANG_CPU_BUILTINS\n"
                                   "#if SAT_STRIP > 8\n"
                                   "  __builtin_prefetch(p);\n"
                                   "#endif\n"
                                   "  __builtin_nontemporal_store(r, q);\n"
                                   "#else\n"
                                   "  vstore8(r, 0, q);\n"
                                   "#endif\n"
                                   "// __builtin_prefetch in a comment\n")
                  .empty());
  EXPECT_EQ(portability_problems("#ifdef CLANG_CPU_BUILTINS\n"
                                 "#else\n"
                                 "  __builtin_prefetch(p);\n"
                                 "#endif\n")
                .size(),
            1u);
  EXPECT_EQ(portability_problems("#ifndef CLANG_CPU_BUILTINS\n  __builtin_expect(x, 1);\n#endif\n")
                .size(),
            1u);
  EXPECT_EQ(portability_problems("float r = native_sqrt(x) + half_exp(y) + mad(a, b, c);\n").size(),
            3u);
  EXPECT_EQ(portability_problems("#pragma OPENCL FP_CONTRACT ON\n").size(), 1u);
  EXPECT_TRUE(portability_problems("#pragma OPENCL FP_CONTRACT OFF\nfloat h = half_w;\n").empty());
}

TEST(KernelPortability, EveryKernelFileUsesOnlyOpenClC) {
  const std::vector<std::filesystem::path> files = kernel_files();
  ASSERT_GT(files.size(), 10u) << kernel_dir();
  for (const std::filesystem::path& f : files)
    for (const std::string& p : portability_problems(read(f)))
      ADD_FAILURE() << f.filename().string() << " " << p;
}

TEST(KernelPortability, ThePreludeTurnsContractionOff) {
  // Before any code: the pragma holds from where it stands to the end of the program.
  const std::string prelude = without_comments(read(kernel_dir() / "prelude.cl"));
  const size_t pragma = prelude.find("#pragma OPENCL FP_CONTRACT OFF");
  ASSERT_NE(pragma, std::string::npos);
  EXPECT_EQ(prelude.find_first_not_of(" \n", 0), pragma);
}

// The diagnostics of a failed build that are not PoCL's own: PoCL vectorizes at launch, not in
// clBuildProgram, so there every `#pragma clang loop vectorize_width` loop is reported as "loop
// not vectorized" (-Wpass-failed, which PoCL's build options cannot turn off) however it is
// vectorized later.
std::vector<std::string> real_diagnostics(const std::string& build_log) {
  std::vector<std::string> real;
  std::istringstream lines(build_log);
  std::string line;
  while (std::getline(lines, line))
    if ((line.rfind("error:", 0) == 0 || line.rfind("warning:", 0) == 0) &&
        line.find("loop not vectorized: the optimizer was unable to perform the requested "
                  "transformation") == std::string::npos)
      real.push_back(line);
  return real;
}

// Every program of the engine's start-up in both kernel shapes (its warm-up builds every
// variant), built again with warnings as errors: with PoCL's CLANG_CPU_BUILTINS, and without, as
// other compilers see the kernels. Every kernel file is among them.
TEST(KernelPortability, TheEnginesProgramsBuildWithWarningsAsErrors) {
  for (const char* shape : {"cpu", "gpu"}) {
    ScopedEnv profile("SHADOW_KERNEL_PROFILE", shape);
    Engine engine;
  }
  const auto built = cl::ProgramCache::built_in_process();
  const std::set<std::pair<std::string, std::string>> programs(built.begin(), built.end());
  std::set<std::string> files;
  for (const auto& [file, options] : programs) {
    files.insert(file);
    for (const char* relaxed : {"-cl-mad-enable", "-cl-fast-relaxed-math",
                                "-cl-unsafe-math-optimizations", "-cl-no-signed-zeros"})
      EXPECT_EQ(options.find(relaxed), std::string::npos) << file << " " << options;
  }
  // Every file with a kernel; the others (the prelude, a family's shared definitions) are
  // included by those.
  for (const std::filesystem::path& f : kernel_files()) {
    if (read(f).find("kernel void") != std::string::npos) {
      EXPECT_TRUE(files.count(f.filename().string())) << f.filename() << " is not built";
    }
  }

  ScopedEnv werror(cl::kExtraOptionsVariable, "-Werror");
  cl::Device device;
  for (auto builtins :
       {cl::ProgramCache::ClangBuiltins::kWhereKnown, cl::ProgramCache::ClangBuiltins::kNone}) {
    cl::ProgramCache strict(device, builtins);
    if (builtins == cl::ProgramCache::ClangBuiltins::kNone) {
      EXPECT_EQ(strict.common_options().find("CLANG_CPU_BUILTINS"), std::string::npos);
    }
    for (const auto& [file, options] : programs) {
      try {
        strict.program(file, options);
      } catch (const cl::Error& e) {
        EXPECT_EQ(e.code(), CL_BUILD_PROGRAM_FAILURE) << e.what();
        for (const std::string& d : real_diagnostics(e.build_log()))
          ADD_FAILURE() << e.what() << "\n" << d;
      }
    }
  }
}

}  // namespace
}  // namespace shadow
