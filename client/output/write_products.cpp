#include "output/write_products.hpp"

#include <stdexcept>
#include <system_error>

#include "output/cube_writer.hpp"
#include "output/exr_writer.hpp"
#include "output/levels_writer.hpp"
#include "output/png_preview.hpp"

namespace shadow::output {

std::vector<WrittenFile> write_products(const std::vector<Texture>& textures,
                                        const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());

  std::vector<WrittenFile> written;
  for (size_t i = 0; i < textures.size(); ++i) {
    const Texture& t = textures[i];
    // A name from the wire must not escape the output directory.
    if (t.name.empty() || t.name.find_first_of("/\\") != std::string::npos || t.name[0] == '.')
      throw std::runtime_error("texture name '" + t.name + "' is not a plain file name");
    std::string stem = t.name;
    std::filesystem::path exr;
    if (is_cube(t) && t.faces == 0) continue;  // nothing rendered, nothing to write
    if (is_cube(t)) {
      exr = dir / (stem + ".exr");
      write_cube_exr(t, exr);
    } else if (is_mip_level(t)) {
      // The levels of one product are consecutive: one "<name>_mips.exr", a PNG of level 0.
      std::vector<const Texture*> levels;
      for (; i < textures.size() && textures[i].kind == t.kind; ++i) levels.push_back(&textures[i]);
      --i;
      const size_t at = t.name.rfind("_mip");
      stem = (at == std::string::npos ? t.name : t.name.substr(0, at)) + "_mips";
      exr = dir / (stem + ".exr");
      write_mip_exr(levels, exr);
    } else if (t.format == PixelFormat::kFloat64) {
      exr = dir / (stem + ".exr");
      write_exr(split_hi_lo(t), exr);
    } else {
      exr = dir / (stem + ".exr");
      write_exr(t, exr);
    }
    const auto png = dir / (stem + ".png");
    if (t.format == PixelFormat::kFloat64) {
      Texture hi = t;  // previewed as float32, range-mapped
      hi.format = PixelFormat::kFloat32;
      hi.data.assign(t.data64.begin(), t.data64.end());
      hi.data64.clear();
      write_png_preview(hi, png);
    } else {
      write_png_preview(t, png);
    }
    for (const auto& file : {exr, png})
      written.push_back({file, &t, std::filesystem::file_size(file)});
  }
  return written;
}

}  // namespace shadow::output
