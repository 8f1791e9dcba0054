// Every file shadowctl writes is a new one: a regular file already at the path is removed first,
// not truncated. ext4 (auto_da_alloc) writes back a file truncated and written again when it is
// closed, so that a crash leaves no empty file; closing a 64 MiB EXR written over the last
// render's then took 56 ms, and a new file's close takes none (docs/benchmarks.md, "What a user
// waits for"). Anything else at the path is left for the open to report.
#pragma once

#include <filesystem>
#include <system_error>

namespace shadow::output {

inline void remove_old_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(std::filesystem::symlink_status(file, ec)))
    std::filesystem::remove(file, ec);  // if it stays, the open says why
}

}  // namespace shadow::output
