#include "output/levels_writer.hpp"

#include <stdexcept>

#include "output/exr_parts.hpp"

namespace shadow::output {

bool is_mip_level(const Texture& t) {
  return t.kind == Product::kShadowMapMips || t.kind == Product::kVisibilityMips ||
         t.kind == Product::kShadowAtlasMips;
}

void write_mip_exr(const std::vector<const Texture*>& levels, const std::filesystem::path& file,
                   std::string_view compression) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  std::vector<ExrPart> parts;
  for (size_t i = 0; i < levels.size(); ++i) {
    const Texture& t = *levels[i];
    if (t.data.size() != size_t{t.width} * t.height * t.channels) fail("level size mismatch");
    ExrPart part = exr_part(t, compression, t.data.data());
    part.header.setName("mip" + std::to_string(i));
    // EXR parts share one display window: level 0's; each level's data window is its own size.
    part.header.displayWindow() = Imath::Box2i(
        Imath::V2i(0, 0), Imath::V2i(int(levels[0]->width) - 1, int(levels[0]->height) - 1));
    parts.push_back(std::move(part));
  }
  write_exr_parts(file, parts);
}

Texture split_hi_lo(const Texture& t) {
  Texture out = t;
  out.data64.clear();
  out.format = PixelFormat::kFloat32;
  out.channels = 2 * t.channels;
  out.data.resize(2 * t.data64.size());
  out.channel_names.clear();  // the server's names, if any, as NAME.hi and NAME.lo
  if (t.channel_names.size() == t.channels)
    for (const std::string& name : t.channel_names)
      out.channel_names.insert(out.channel_names.end(), {name + ".hi", name + ".lo"});
  for (size_t i = 0; i < t.data64.size(); ++i) {
    const float hi = static_cast<float>(t.data64[i]);
    out.data[2 * i] = hi;
    out.data[2 * i + 1] = static_cast<float>(t.data64[i] - double(hi));
  }
  return out;
}

}  // namespace shadow::output
