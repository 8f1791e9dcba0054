// What shadowctl prints after a render: the files it wrote (and the cube textures with no face,
// which write none), how the light was fitted (for a cube: each face, rendered or skipped and
// why), a virtual map's pages, and the passes with their timings.
#pragma once

#include <string>
#include <vector>

#include "output/write_products.hpp"
#include "shadow/v1/shadow.pb.h"
#include "shadowctl/render_to_files.hpp"
#include "wire/types.hpp"

namespace shadow::ctl {

// "12.0 MiB", "345.6 KiB", "512 B".
std::string human_bytes(uintmax_t bytes);

// ... then the client's timeline: when the header and the last chunk arrived and the files were
// written, against the device time.
std::string format_report(const RenderResult& result, const std::vector<output::WrittenFile>& files,
                          const Timeline& timeline);

// "virtual pages: requested 412, resident 412, rendered 37, coarsened 0 pixels, pool 64 MiB"
// (TECHNIQUE_VIRTUAL's counts; the pool in MiB, with one decimal unless whole).
std::string format_virtual_pages(const VirtualPageCounts& pages);

// --estimate's lines: the device time (a sequence's in all, per frame beside it), the memory and
// reply bytes, the limits they are held against and whether the server would admit the work.
std::string format_price(const v1::Price& price);

// `shadowctl stats`: the device, the load now, requests by status, queue and run time
// percentiles, the scene cache, the passes that took the most device time and the tenants that
// used the most, at most kStatisticsRows of each: one screen whatever the server's history
// (`--json` prints the whole document).
std::string format_statistics(const v1::Statistics& stats);
inline constexpr size_t kStatisticsRows = 12;

}  // namespace shadow::ctl
