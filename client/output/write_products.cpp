#include "output/write_products.hpp"

#include <stdexcept>
#include <system_error>

#include "output/cube_writer.hpp"
#include "output/exr_writer.hpp"
#include "output/half.hpp"
#include "output/levels_writer.hpp"
#include "output/png_preview.hpp"

namespace shadow::output {
namespace {

// A float16 texture with its values as floats (exact) in `data`, still marked kFloat16 so its
// EXR stores HALF channels: the writers read `data`.
Texture widened(const Texture& t) {
  Texture wide = t;
  wide.data = halves_to_floats(t.data16);
  wide.data16.clear();
  return wide;
}

void write_preview(const Texture& t, const std::filesystem::path& png, Preview preview) {
  const uint32_t edge = preview == Preview::kFull ? 0 : kPreviewEdge;
  if (t.format != PixelFormat::kFloat64) return write_png_preview(t, png, edge);
  Texture hi = t;  // previewed as float32, range-mapped
  hi.format = PixelFormat::kFloat32;
  hi.data.assign(t.data64.begin(), t.data64.end());
  hi.data64.clear();
  write_png_preview(hi, png, edge);
}

}  // namespace

std::filesystem::path exr_path(const Texture& t, const std::filesystem::path& dir) {
  if (t.name.empty() || t.name.find_first_of("/\\") != std::string::npos || t.name[0] == '.')
    throw std::runtime_error("texture name '" + t.name + "' is not a plain file name");
  return dir / (t.name + ".exr");
}

bool is_plain(const Texture& t) {
  return !is_cube(t) && !is_mip_level(t) && t.format == PixelFormat::kFloat32;
}

std::vector<WrittenFile> write_products(const std::vector<Texture>& textures,
                                        const std::filesystem::path& dir,
                                        const OutputOptions& options,
                                        const std::vector<bool>& exr_written) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());

  const std::string_view compression = options.exr_compression;
  std::vector<WrittenFile> written;
  // Float16 textures as floats, for the writers; `written` still points at `textures`.
  std::vector<Texture> wide(textures.size());
  for (size_t i = 0; i < textures.size(); ++i)
    if (textures[i].format == PixelFormat::kFloat16) wide[i] = widened(textures[i]);
  const auto values = [&](size_t i) -> const Texture& {
    return textures[i].format == PixelFormat::kFloat16 ? wide[i] : textures[i];
  };
  for (size_t i = 0; i < textures.size(); ++i) {
    const size_t first = i;  // a mip chain's first level
    const Texture& t = values(i);
    std::filesystem::path exr = exr_path(t, dir);
    if (is_cube(t) && t.faces == 0) continue;  // nothing rendered, nothing to write
    if (i < exr_written.size() && exr_written[i]) {
      // written by the caller
    } else if (is_cube(t)) {
      write_cube_exr(t, exr, compression);
    } else if (is_mip_level(t)) {
      // The levels of one product are consecutive: one "<name>_mips.exr", a PNG of level 0.
      std::vector<const Texture*> levels;
      for (; i < textures.size() && textures[i].kind == t.kind; ++i) levels.push_back(&values(i));
      --i;
      const size_t at = t.name.rfind("_mip");
      exr = dir / ((at == std::string::npos ? t.name : t.name.substr(0, at)) + "_mips.exr");
      write_mip_exr(levels, exr, compression);
    } else if (t.format == PixelFormat::kFloat64) {
      write_exr(split_hi_lo(t), exr, compression);
    } else {
      write_exr(t, exr, compression);
    }
    written.push_back({exr, &textures[first], std::filesystem::file_size(exr)});
    if (options.preview == Preview::kNone) continue;
    auto png = exr;
    png.replace_extension(".png");
    write_preview(t, png, options.preview);
    written.push_back({png, &textures[first], std::filesystem::file_size(png)});
  }
  return written;
}

}  // namespace shadow::output
