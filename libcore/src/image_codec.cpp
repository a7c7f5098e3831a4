#include "image_codec.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "ctk/core/error.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModule = "libctk_image_codec_oiio.so";

// Where the module may be, in order: named by CTK_IMAGE_CODEC; beside the program or Python
// module that contains this code, or where an install puts it relative to one (bin/ctk ->
// lib/ctk/, lib/python3*/dist-packages/ctk/_ctk*.so -> lib/ctk/); the build tree; the configured install.
std::vector<fs::path> candidates() {
  std::vector<fs::path> places;
  if (const char* named = std::getenv("CTK_IMAGE_CODEC"); named && *named) places.emplace_back(named);
  Dl_info self{};
  if (dladdr(reinterpret_cast<void*>(&image_codec), &self) && self.dli_fname) {
    const fs::path dir = fs::absolute(self.dli_fname).parent_path();
    places.push_back(dir / kModule);
    places.push_back(dir / ".." / CTK_INSTALL_LIBDIR / "ctk" / kModule);
    places.push_back(dir / ".." / ".." / ".." / ".." / CTK_INSTALL_LIBDIR / "ctk" / kModule);
  }
  places.emplace_back(CTK_IMAGE_CODEC_BUILD_PATH);
  places.emplace_back(CTK_IMAGE_CODEC_INSTALL_PATH);
  return places;
}

const ImageCodec* load() {
  std::string tried;
  for (const fs::path& place : candidates()) {
    std::error_code ec;
    if (!fs::is_regular_file(place, ec)) {
      tried += "\n  " + place.lexically_normal().string() + " (absent)";
      continue;
    }
    // Never closed: the codec lives as long as the process.
    void* module = dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    const char* error = module ? nullptr : dlerror();
    if (module) {
      using Entry = const ImageCodec* (*)();
      if (auto entry = reinterpret_cast<Entry>(dlsym(module, "ctk_image_codec"))) return entry();
      error = "no entry point ctk_image_codec";
    }
    tried += "\n  " + place.lexically_normal().string() + " (" + error + ")";
  }
  throw std::runtime_error(
      "ctk's image codec module (OpenImageIO, for images other than plain TIFFs) cannot be loaded; "
      "set CTK_IMAGE_CODEC to its path. Looked in:" +
      tried);
}

}  // namespace

const ImageCodec& image_codec() {
  static std::once_flag once;
  static const ImageCodec* codec = nullptr;
  std::call_once(once, [] { codec = load(); });
  return *codec;
}

std::unique_ptr<CodecReader> open_with_codec(const fs::path& file, const std::string& what) {
  try {
    return image_codec().open(file);
  } catch (const std::runtime_error& e) {
    throw InputError(file.string(), "", "cannot read the " + what + ": " + e.what());
  }
}

}  // namespace ctk
