#include "output/cube_writer.hpp"

#include <stdexcept>

#include <OpenEXR/ImfStringAttribute.h>

#include "output/exr_parts.hpp"

namespace shadow::output {

bool is_cube(const Texture& t) {
  return !t.cube_faces.empty() || t.faces != 1;
}

void write_cube_exr(const Texture& cube, const std::filesystem::path& file,
                    std::string_view compression) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  if (cube.faces == 0) fail("the cube has no rendered face to write");
  if (cube.cube_faces.size() != cube.faces)
    fail("the cube describes " + std::to_string(cube.cube_faces.size()) + " faces for " +
         std::to_string(cube.faces) + " faces of data");
  if (cube.width == 0 || cube.height == 0 || cube.channels == 0) fail("empty texture");
  const size_t face_floats = size_t{cube.width} * cube.height * cube.channels;
  if (cube.data.size() != face_floats * cube.faces)
    fail("texture holds " + std::to_string(cube.data.size()) + " floats, expected " +
         std::to_string(face_floats * cube.faces));

  std::vector<ExrPart> parts;
  for (size_t i = 0; i < cube.faces; ++i) {
    const TextureFace& face = cube.cube_faces[i];
    Texture view;  // the cube's shape with this face's matrices, without the data
    view.kind = cube.kind;
    view.width = cube.width;
    view.height = cube.height;
    view.channels = cube.channels;
    view.world_to_ndc = face.world_to_ndc;
    view.world_to_camera = face.world_to_camera;
    ExrPart part = exr_part(view, compression, cube.data.data() + i * face_floats);
    part.header.setName(face.name);
    part.header.insert("textureformat", Imf::StringAttribute("CubeFace Shadow"));
    parts.push_back(std::move(part));
  }
  write_exr_parts(file, parts);
}

}  // namespace shadow::output
