// What the scene loaders share to stay safe on hostile files: overflow-checked arithmetic, a
// bounded file reader and the one budget that every allocation the loader makes is charged
// against before it happens.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "scenes/scene_loader.hpp"

namespace shadow::scenes {

inline std::optional<uint64_t> checked_add(uint64_t a, uint64_t b) {
  uint64_t r;
  if (__builtin_add_overflow(a, b, &r)) return std::nullopt;
  return r;
}

inline std::optional<uint64_t> checked_mul(uint64_t a, uint64_t b) {
  uint64_t r;
  if (__builtin_mul_overflow(a, b, &r)) return std::nullopt;
  return r;
}

// Thrown when a charge would pass the budget; a std::runtime_error that already names the file.
struct BudgetExceeded : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Counts the bytes read for one scene (the input) and the bytes the loader may build from them:
// limits.bytes_per_input_byte * input + limits.slack_bytes. Charges only grow; anything that
// would pass the limit throws BudgetExceeded "<file>: <what> needs N bytes ...".
class LoadBudget {
 public:
  LoadBudget(const std::filesystem::path& file, const LoadLimits& limits)
      : file_(file.string()), limits_(limits) {}

  const LoadLimits& limits() const { return limits_; }
  uint64_t input_bytes() const { return input_; }
  uint64_t charged_bytes() const { return charged_; }
  uint64_t limit_bytes() const;

  // A file of `bytes` is about to be read for this scene (checked against the file limits).
  // `name` is the file as the error should name it.
  void add_input(uint64_t bytes, const std::string& name);

  // Charges `bytes`, or count * element_bytes (overflow-checked), before they are allocated.
  void charge(uint64_t bytes, std::string_view what);
  void charge(uint64_t count, uint64_t element_bytes, std::string_view what);

 private:
  [[noreturn]] void exceeded(std::string_view what, std::optional<uint64_t> bytes) const;

  std::string file_;
  LoadLimits limits_;
  uint64_t input_ = 0;
  uint64_t charged_ = 0;
};

// Makes room for `extra` more elements in `v`, growing its capacity geometrically, and charges
// each new allocation to `budget` before it is made (so the charges cover what a growing vector
// really holds: the sum of its allocations is at most twice its final capacity).
template <typename T>
void grow(std::vector<T>& v, size_t extra, LoadBudget& budget, std::string_view what) {
  if (extra <= v.capacity() - v.size()) return;
  const size_t capacity = std::max(v.size() + extra, 2 * v.capacity());
  budget.charge(capacity, sizeof(T), what);
  v.reserve(capacity);
}

// The whole file, after checking its size against the budget's file limits (and adding it to
// the input). Throws std::runtime_error naming the file.
std::string read_file_bounded(const std::filesystem::path& path, LoadBudget& budget);
void read_file_bounded(const std::filesystem::path& path, LoadBudget& budget,
                       std::vector<unsigned char>& into);

// A token from a hostile file, fit for an error message: quoted, non-printable bytes as \xNN,
// long tokens cut.
std::string quote_token(std::string_view token);

}  // namespace shadow::scenes
