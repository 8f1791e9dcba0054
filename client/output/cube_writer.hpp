// Cube shadow maps (TECHNIQUE_CUBE) as files: one multi-subimage EXR with a subimage per face.
#pragma once

#include <filesystem>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

// True for a cube texture: it describes its faces (cube_faces), or holds other than one face
// (a cube with no rendered face has faces = 0 and no cube_faces).
bool is_cube(const Texture& t);

// Writes the faces of a cube texture in data order, one EXR subimage (part) per face, named
// after it ("+x" .. "-z", as oiio:subimagename), each with the face's own `worldtoNDC` and
// `worldtocamera` (the convention of write_exr) and `textureformat` = "CubeFace Shadow".
// Channels as write_exr ("Z" for a shadow map). A cube with no face has nothing to write and
// is refused, since an EXR needs at least one part. Throws std::runtime_error naming the file.
void write_cube_exr(const Texture& cube, const std::filesystem::path& file,
                    std::string_view compression = kDefaultExrCompression);

}  // namespace shadow::output
