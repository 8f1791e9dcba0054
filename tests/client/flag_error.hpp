// For shadowctl flag tests: the FlagError build_request throws for these flags, as text.
#pragma once

#include <string>

#include "shadowctl/args.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {

// e.what() of the FlagError, or "(no error)" when the request builds.
inline std::string flag_error_of(const RequestFlags& flags) {
  try {
    build_request(flags);
  } catch (const FlagError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace shadow::ctl
