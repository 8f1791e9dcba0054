#include "output/exr_parts.hpp"

#include <stdexcept>

namespace shadow::output {

void write_exr_parts(const std::filesystem::path& file, const std::vector<OIIO::ImageSpec>& specs,
                     const std::vector<const float*>& pixels) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  if (specs.empty() || specs.size() != pixels.size()) fail("no parts to write");
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) fail("cannot create an EXR writer: " + OIIO::geterror());
  if (!out->supports("multiimage")) fail("the EXR writer cannot write several parts");
  if (!out->open(file.string(), int(specs.size()), specs.data())) fail(out->geterror());
  for (size_t i = 0; i < specs.size(); ++i) {
    if (i > 0 && !out->open(file.string(), specs[i], OIIO::ImageOutput::AppendSubimage))
      fail(out->geterror());
    if (!out->write_image(OIIO::TypeDesc::FLOAT, pixels[i])) fail(out->geterror());
  }
  if (!out->close()) fail(out->geterror());
}

}  // namespace shadow::output
