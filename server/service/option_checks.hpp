// shadow-server's checks of its option values, so that a value that cannot work stops the
// start naming its flag (issue 40) instead of breaking the service later.
#pragma once

#include <chrono>
#include <climits>
#include <cmath>

#include <CLI/CLI.hpp>

namespace shadow::service {

// A reader may stall this long at most: past a day it is holding its reply's memory, not slow.
constexpr double kMaxStallSeconds = 86400;
// gRPC takes connection ages in milliseconds in an int (about 24.8 days).
constexpr double kMaxConnectionAgeSeconds = INT_MAX / 1000;

// A finite number of `unit` in [low, high], or (low, high] when `low_open`. CLI11's own ranges
// let NaN through (every comparison with it is false), and 1e300 s overflows the milliseconds.
CLI::Validator finite_in(const char* unit, double low, bool low_open, double high = HUGE_VAL);

// A whole number >= `min`. CLI11 2.1 reads "-1" into an unsigned option as 2^64 - 1 (strtoull
// wraps it), and a number past 2^64 as 2^64 - 1 as well; it refuses other non-numbers itself.
CLI::Validator whole_number(unsigned long long min = 0);

// HOST:PORT, an IPv6 host in brackets ("[::1]:0"). gRPC would bind port 99999 as 34463 (its low
// 16 bits).
extern const CLI::Validator kListenAddress;

// TENANT=WEIGHT with a finite weight in (0, 1e6] (--tenant-weight).
extern const CLI::Validator kTenantWeight;

// Seconds as milliseconds, rounded up: a positive number of seconds never becomes 0 ms, which
// means "never" or "at once".
std::chrono::milliseconds milliseconds(double seconds);

}  // namespace shadow::service
