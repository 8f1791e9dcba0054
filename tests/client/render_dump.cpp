// render-dump: renders one binary RenderRequest through the C++ client library and writes what
// came back, for tests that compare another client (the Python one) with it:
//   OUT/NAME.bin   the texture's values as they are in memory (float32 or float64)
//   OUT/NAME.txt   "world_to_ndc" / "world_to_camera" lines of 16 values (row-major, %.9g),
//                  "face NAME" + its world_to_ndc per cube face, "channel NAME" per channel
//   OUT/scene_key  the x-scene-id the client sent
// Usage: render-dump TARGET REQUEST.pb OUT [--tls-ca FILE] [--token TOKEN]
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "shadow_client.hpp"
#include "wire/scene_id.hpp"

namespace {

void write_matrix(std::ostream& out, const char* label, const glm::mat4& m) {
  out << label;
  char value[32];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(value, sizeof value, " %.9g", m[c][r]);  // GLM is [column][row]
      out << value;
    }
  out << '\n';
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: render-dump TARGET REQUEST.pb OUT [--tls-ca FILE] [--token TOKEN]\n";
    return 2;
  }
  shadow::client::Credentials credentials;
  for (int i = 4; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--tls-ca") == 0)
      credentials.tls_ca = argv[i + 1];
    else if (std::strcmp(argv[i], "--token") == 0)
      credentials.token = argv[i + 1];
    else {
      std::cerr << "render-dump: unknown option " << argv[i] << '\n';
      return 2;
    }
  }
  std::ifstream in(argv[2], std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  shadow::v1::RenderRequest request;
  if (!in || !request.ParseFromString(bytes.str())) {
    std::cerr << "render-dump: cannot read a RenderRequest from " << argv[2] << '\n';
    return 2;
  }
  try {
    shadow::client::ShadowClient client(argv[1], credentials);
    const shadow::RenderResult result = client.render(request);
    const std::string out = argv[3];
    for (const shadow::Texture& t : result.textures) {
      std::ofstream bin(out + "/" + t.name + ".bin", std::ios::binary);
      if (t.format == shadow::PixelFormat::kFloat64)
        bin.write(reinterpret_cast<const char*>(t.data64.data()), t.data64.size() * sizeof(double));
      else
        bin.write(reinterpret_cast<const char*>(t.data.data()), t.data.size() * sizeof(float));
      std::ofstream txt(out + "/" + t.name + ".txt");
      write_matrix(txt, "world_to_ndc", t.world_to_ndc);
      write_matrix(txt, "world_to_camera", t.world_to_camera);
      for (const shadow::TextureFace& f : t.cube_faces) {
        txt << "face " << f.name << '\n';
        write_matrix(txt, "face_world_to_ndc", f.world_to_ndc);
      }
      for (const std::string& c : t.channel_names) txt << "channel " << c << '\n';
      if (!bin || !txt) {
        std::cerr << "render-dump: cannot write " << t.name << " in " << out << '\n';
        return 1;
      }
    }
    std::ofstream(out + "/scene_key") << shadow::scene_id(request.scene());
    std::cout << result.textures.size() << " textures\n";
  } catch (const shadow::client::RpcError& e) {
    std::cerr << "render-dump: " << e.code() << ": " << e.what() << '\n';
    return 1;
  }
  return 0;
}
