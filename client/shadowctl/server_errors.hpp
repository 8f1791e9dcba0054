// The server's errors speak proto: they start with the field's path and name enum values, e.g.
// "shadow_map.technique: TECHNIQUE_LISPSM needs a directional light". shadowctl's user typed
// flags; this is the one table from proto field paths and enum value names to the shadowctl flags
// and values that set them, and the note shadowctl adds to such an error.
#pragma once

#include <string>
#include <string_view>

#include <grpcpp/support/status.h>

namespace shadow::ctl {

// The shadowctl flag (and value form) that sets the field at a proto path, e.g. "--map-size" for
// "shadow_map.size", "--light-size" for "lights[2].size", "--scene" for
// "scene.meshes[3].indices[17]" (the longest known prefix decides); "" for a field no flag sets.
// A sequence's "base." prefix is the flags'; "frames[i]." names --frames.
std::string flag_for_field(std::string_view field);

// The flag and value for a proto enum value name, e.g. "--technique lispsm" for
// "TECHNIQUE_LISPSM", "--fit scene" for "MAP_FIT_SCENE"; "" for a name it does not know. Built
// from the name tables of wire/names.hpp, so every value shadowctl can spell is here.
std::string flag_for_enum_value(std::string_view name);

// The note shadowctl appends to a server error of `code` (INVALID_ARGUMENT or
// RESOURCE_EXHAUSTED; "" for any other): " (shadowctl: shadow_map.technique is --technique,
// TECHNIQUE_LISPSM is --technique lispsm)". It names the message's leading field and each enum
// value in it, leaving out what the message already spells as a flag, and suggests
// --atlas-generate-uvs for a mesh's UVs that the atlas cannot use. "" when there is nothing to say.
std::string flag_note(grpc::StatusCode code, std::string_view message);

}  // namespace shadow::ctl
