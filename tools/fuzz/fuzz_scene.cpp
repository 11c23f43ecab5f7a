// libFuzzer harness over the scene loaders (loadScene: OBJ + MTL, glTF, glb, scene JSON; scene/src/load*.cpp).
// Scene files come from artists and downloads: bad data must throw InputError (the CLI's exit 2), never crash,
// hang, leak, or throw anything else (which the CLI would report as an internal failure, exit 1).
//
// Input layout: byte 0 picks the format (mod 4: OBJ, glTF, glb, scene JSON); the rest is the main file, up to
// a line "#--" after which comes the companion file it may name: the OBJ's material library m.mtl, the glTF's
// buffer b.bin, the scene JSON's mesh m.obj. Both are written to a per-process temporary folder and
// loaded by path, as the CLI loads them. Built by `make fuzz`; seeds: tools/fuzz/make_seeds.sh.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace {

const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("tetraprobe_fuzz_scene." + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void write(const std::filesystem::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kMain[] = {"s.obj", "s.gltf", "s.glb", "s.scene.json"};
  static const char* const kCompanion[] = {"m.mtl", "b.bin", "b.bin", "m.obj"};
  const int format = data[0] % 4;
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  const size_t cut = rest.find("\n#--\n");
  const std::string_view main = rest.substr(0, cut);
  const std::string_view companion =
      cut == std::string_view::npos ? std::string_view() : rest.substr(cut + 5);
  const std::filesystem::path path = folder() / kMain[format];
  write(path, main);
  write(folder() / kCompanion[format], companion);
  try {
    const tetraprobe::Scene scene = tetraprobe::loadScene(path.string());
    (void)scene;
  } catch (const tetraprobe::InputError&) {
    // the expected outcome for bad input
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_scene: %s threw a non-InputError: %s\n", kMain[format], e.what());
    std::abort();
  }
  return 0;
}
