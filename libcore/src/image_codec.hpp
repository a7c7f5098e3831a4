#pragma once
// Image formats beyond the plain TIFFs ctk reads and writes itself (EXR, tiled or colour TIFFs,
// PNG and whatever else OpenImageIO reads), through OpenImageIO in a module loaded on first use.
// OpenImageIO as Debian builds it brings about 260 shared libraries (video codecs, GDAL, DICOM):
// linked into the command, loading them cost every run about 0.45 s of CPU before main (perf stat
// on `ctk --version`, Zen 5), for the few runs that read such a file.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ctk {

/// One subimage's header as the file states it.
struct CodecHeader {
  int width = 0, height = 0, depth = 1, channels = 0;
  int integer_bits = 0;     // 8, 16 or 32 for unsigned integer samples, 0 otherwise
  std::string description;  // ImageDescription ("" when absent)
};

/// An open image file; std::runtime_error with the library's message when something fails.
class CodecReader {
 public:
  virtual ~CodecReader() = default;
  /// Moves to subimage `index` (a TIFF page); false when there is none.
  virtual bool seek(int index) = 0;
  virtual CodecHeader header() const = 0;
  /// The current subimage's first channel as float; integer samples scaled to [0, 1] (OpenImageIO's
  /// convention: the caller turns them back into counts). A truncated file throws.
  virtual void read_first_channel(float* out) = 0;
};

class ImageCodec {
 public:
  virtual ~ImageCodec() = default;
  /// std::runtime_error when the file cannot be opened as an image.
  virtual std::unique_ptr<CodecReader> open(const std::filesystem::path& file) const = 0;
  /// Writes one channel of floats (`integer_bits` 0) or 8/16-bit unsigned samples to `tmp` in the
  /// format `file`'s extension names.
  virtual void write(const std::filesystem::path& file, const std::filesystem::path& tmp, int cols, int rows, int integer_bits,
                     const void* pixels, const std::string& description) const = 0;
};

/// The codec module, loaded on first call (thread safe); std::runtime_error naming the places it
/// looked when it cannot be loaded.
const ImageCodec& image_codec();

/// `file` opened through the codec; InputError naming the file ("cannot read the <what>: ...")
/// when it cannot be.
std::unique_ptr<CodecReader> open_with_codec(const std::filesystem::path& file, const std::string& what);

}  // namespace ctk
