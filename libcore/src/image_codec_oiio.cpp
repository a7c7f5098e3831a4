// The image codec module (image_codec.hpp) over OpenImageIO, built as a shared module of its own
// and loaded by image_codec.cpp on first use.
#include <OpenImageIO/imageio.h>

#include <stdexcept>

#include "image_codec.hpp"

namespace ctk {
namespace {

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

int integer_bits(const TypeDesc& format) {
  if (format == TypeDesc::UINT8) return 8;
  if (format == TypeDesc::UINT16) return 16;
  if (format == TypeDesc::UINT32) return 32;
  return 0;
}

class OiioReader final : public CodecReader {
 public:
  explicit OiioReader(std::unique_ptr<ImageInput> in) : in_(std::move(in)) {}
  bool seek(int index) override { return in_->seek_subimage(index, 0); }
  CodecHeader header() const override {
    const ImageSpec& s = in_->spec();
    return {s.width, s.height, s.depth, s.nchannels, integer_bits(s.format), s.get_string_attribute("ImageDescription")};
  }
  void read_first_channel(float* out) override {
    // A truncated file may read "successfully" with an error recorded: check both, after clearing
    // what an earlier seek past the last subimage recorded.
    (void)in_->geterror();
    if (!in_->read_image(in_->current_subimage(), 0, 0, 1, TypeDesc::FLOAT, out) || in_->has_error())
      throw std::runtime_error(in_->geterror());
  }

 private:
  std::unique_ptr<ImageInput> in_;
};

class OiioCodec final : public ImageCodec {
 public:
  std::unique_ptr<CodecReader> open(const std::filesystem::path& file) const override {
    auto in = ImageInput::open(file.string());
    if (!in) throw std::runtime_error(OIIO::geterror());
    return std::make_unique<OiioReader>(std::move(in));
  }
  void write(const std::filesystem::path& file, const std::filesystem::path& tmp, int cols, int rows, int bits,
             const void* pixels, const std::string& description) const override {
    auto out = ImageOutput::create(file.string());
    if (!out) throw std::runtime_error("no writer for this format: " + OIIO::geterror());
    const TypeDesc type = bits == 8 ? TypeDesc::UINT8 : bits == 16 ? TypeDesc::UINT16 : TypeDesc::FLOAT;
    ImageSpec spec(cols, rows, 1, type);
    if (!description.empty()) spec.attribute("ImageDescription", description);
    if (!out->open(tmp.string(), spec) || !out->write_image(type, pixels) || !out->close())
      throw std::runtime_error("write failed: " + out->geterror());
  }
};

}  // namespace
}  // namespace ctk

// The module's one entry point, looked up by name.
extern "C" __attribute__((visibility("default"))) const ctk::ImageCodec* ctk_image_codec() {
  static const ctk::OiioCodec codec;
  return &codec;
}
