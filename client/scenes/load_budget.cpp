#include "scenes/load_budget.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace shadow::scenes {
namespace {

std::string size_text(uint64_t bytes) {
  if (bytes >= (1u << 20) && bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

// Closes a file descriptor at scope exit.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

uint64_t LoadBudget::limit_bytes() const {
  // Saturates: a limit past 2^64 is no limit worth computing.
  const auto scaled = checked_mul(input_, limits_.bytes_per_input_byte);
  const auto total = scaled ? checked_add(*scaled, limits_.slack_bytes) : std::nullopt;
  return total ? *total : UINT64_MAX;
}

void LoadBudget::add_input(uint64_t bytes, const std::string& name) {
  if (bytes > limits_.max_file_bytes)
    throw std::runtime_error(file_ + ": " + name + " is " + std::to_string(bytes) +
                             " bytes, more than the " + size_text(limits_.max_file_bytes) +
                             " a scene file may have");
  const auto total = checked_add(input_, bytes);
  if (!total || *total > limits_.max_total_input_bytes)
    throw std::runtime_error(file_ + ": reading " + name + " would take the files read for this " +
                             "scene past " + size_text(limits_.max_total_input_bytes));
  input_ = *total;
}

void LoadBudget::charge(uint64_t bytes, std::string_view what) {
  const auto total = checked_add(charged_, bytes);
  if (!total || *total > limit_bytes()) exceeded(what, bytes);
  charged_ = *total;
}

void LoadBudget::charge(uint64_t count, uint64_t element_bytes, std::string_view what) {
  const auto bytes = checked_mul(count, element_bytes);
  if (!bytes) exceeded(what, std::nullopt);
  charge(*bytes, what);
}

void LoadBudget::exceeded(std::string_view what, std::optional<uint64_t> bytes) const {
  throw BudgetExceeded(
      file_ + ": " + std::string(what) + " needs " +
      (bytes ? std::to_string(*bytes) + " bytes" : std::string("more than 2^64 bytes")) +
      ", more than the loader allows for a scene read from " + std::to_string(input_) + " bytes (" +
      std::to_string(limits_.bytes_per_input_byte) + " per byte read + " +
      size_text(limits_.slack_bytes) + ", " + std::to_string(charged_) + " already used)");
}

namespace {

template <typename Bytes>
void read_bounded(const std::filesystem::path& path, LoadBudget& budget, Bytes& bytes) {
  const std::string name = path.string();
  Fd f;
  // O_NONBLOCK: a FIFO must not hang the open; it is rejected as not a regular file below.
  f.fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (f.fd < 0)
    throw std::runtime_error(name + ": cannot open: " + std::string(std::strerror(errno)));
  struct stat st {};
  if (::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode))
    throw std::runtime_error(name + ": not a regular file");
  const uint64_t size = static_cast<uint64_t>(st.st_size);
  budget.add_input(size, name);

  bytes.assign(size, 0);
  size_t got = 0;
  while (got < size) {  // a file that grows meanwhile is read only up to its size at open
    const ssize_t n = ::read(f.fd, bytes.data() + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw std::runtime_error(name + ": read failed: " + std::string(std::strerror(errno)));
    if (n == 0) break;
    got += static_cast<size_t>(n);
  }
  bytes.resize(got);
}

}  // namespace

std::string read_file_bounded(const std::filesystem::path& path, LoadBudget& budget) {
  std::string bytes;
  read_bounded(path, budget, bytes);
  return bytes;
}

void read_file_bounded(const std::filesystem::path& path, LoadBudget& budget,
                       std::vector<unsigned char>& into) {
  read_bounded(path, budget, into);
}

std::string quote_token(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\' && c != '\'') {
      out += static_cast<char>(c);
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > kMax) out += "...";
  return out + "'";
}

}  // namespace shadow::scenes
