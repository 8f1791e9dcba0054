#include "output/write_products.hpp"

#include <stdexcept>
#include <system_error>

#include "output/exr_writer.hpp"
#include "output/png_preview.hpp"

namespace shadow::output {

std::vector<WrittenFile> write_products(const std::vector<Texture>& textures,
                                        const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());

  std::vector<WrittenFile> written;
  for (const Texture& t : textures) {
    // A name from the wire must not escape the output directory.
    if (t.name.empty() || t.name.find_first_of("/\\") != std::string::npos || t.name[0] == '.')
      throw std::runtime_error("texture name '" + t.name + "' is not a plain file name");
    const auto exr = dir / (t.name + ".exr");
    const auto png = dir / (t.name + ".png");
    write_exr(t, exr);
    write_png_preview(t, png);
    for (const auto& file : {exr, png})
      written.push_back({file, &t, std::filesystem::file_size(file)});
  }
  return written;
}

}  // namespace shadow::output
