// shadowctl's flag values, strings → engine values. Syntax only: the server validates meaning
// (zero directions, ranges) and names the field. Errors throw FlagError naming the flag. Enum
// values are spelled as in their table in wire/names.hpp; an unknown name lists the table's.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::ctl {

class FlagError : public std::invalid_argument {
 public:
  FlagError(std::string_view flag, const std::string& why)
      : std::invalid_argument(std::string(flag) + ": " + why), flag_(flag) {}
  const std::string& flag() const { return flag_; }

 private:
  std::string flag_;
};

// A finite decimal number, e.g. "0.5", "-3", "1e-4".
float parse_float(std::string_view text, std::string_view flag);
// A non-negative integer that fits in 32 bits (the field's range is the server's rule: see
// check_like_the_server).
uint32_t parse_uint(std::string_view text, std::string_view flag);
// "X,Y,Z".
glm::vec3 parse_vec3(std::string_view text, std::string_view flag);

struct ImageSize {
  uint32_t width = 0;
  uint32_t height = 0;
};
// "WxH", e.g. "1280x720", each at least 1.
ImageSize parse_size(std::string_view text, std::string_view flag);

// "directional:DX,DY,DZ" | "spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG" | "point:PX,PY,PZ" (the kind from
// names::kLightTypes). Size stays 0.
Light parse_light(std::string_view text, std::string_view flag);

// Comma-separated names from names::kProducts (shadowmap, visibility, ...), each once.
std::vector<Product> parse_products(std::string_view text, std::string_view flag);

// A name from names::kFilterKinds: "hard" | "pcf2x2" | "poisson" | "pcss" | "blur" | "csm" |
// "pcss_csm".
FilterKind parse_filter(std::string_view text, std::string_view flag);

// A name from names::kCsmStorages: "float32" | "float16".
CsmStorage parse_csm_storage(std::string_view text, std::string_view flag);

// A name from names::kCsmLookups: "mips" | "sat".
CsmLookup parse_csm_lookup(std::string_view text, std::string_view flag);

// "on" | "off" | "true" | "false".
bool parse_bool(std::string_view text, std::string_view flag);

// "INSTANCE:CLASS", e.g. "0:1": instance 0 is a receiver of blur class 1.
struct ReceiverClass {
  uint32_t instance = 0;
  uint32_t receiver_class = 0;
};
ReceiverClass parse_receiver_class(std::string_view text, std::string_view flag);

// A name from names::kTechniques: "uniform" | "psm" | "cube" | "psm_cube" | "lispsm" | "auto" |
// "virtual".
Technique parse_technique(std::string_view text, std::string_view flag);
// A name from names::kPsmCasters: "inverse-projection" | "slide-back".
PsmCasters parse_psm_casters(std::string_view text, std::string_view flag);
// A name from names::kPsmNear: "receivers" | "camera" | "virtual-slide-back".
PsmNear parse_psm_near(std::string_view text, std::string_view flag);
// A name from names::kPixelFormats: "float32" | "float64" | "float16".
PixelFormat parse_pixel_format(std::string_view text, std::string_view flag);
// A name from names::kMapFits: "view" | "scene".
MapFit parse_map_fit(std::string_view text, std::string_view flag);

// A name from names::kChunkCompressions: "none" | "zstd".
ChunkCompression parse_chunk_compression(std::string_view text, std::string_view flag);
// A name from output::kExrCompressions: "auto" | "none" | "rle" | "zips" | "zip" | "piz".
std::string parse_exr_compression(std::string_view text, std::string_view flag);
// "png" | "full" | "none": which PNG previews are written (output::Preview).
output::Preview parse_preview(std::string_view text, std::string_view flag);

}  // namespace shadow::ctl
