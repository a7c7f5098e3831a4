#pragma once
// Tomography frames in HDF5/NeXus files following the NXtomo application definition (what
// synchrotrons, tomwer and CIL write): every frame in one dataset, an image key per frame telling
// projections from flats and darks, a rotation angle per frame, and the detector's pixel size and
// distances where the file gives them, converted to mm from their `units` attributes.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ctk/core/image_io.hpp"

namespace ctk {

/// NXtomo's image key (NXdetector/image_key).
enum class NxFrameKind { projection = 0, flat = 1, dark = 2, invalid = 3 };

struct NxTomo {
  std::filesystem::path file;
  std::string entry;      // "/entry", the NXentry whose definition is NXtomo
  std::string data_path;  // the frames: [frames][rows][cols], row 0 first
  int frames = 0, rows = 0, cols = 0;
  bool integer_data = false;               // counts stored as integers (kept exact as float)
  std::vector<NxFrameKind> kind;           // per frame
  std::vector<double> rotation_angle_deg;  // per frame
  std::optional<double> x_pixel_size_mm, y_pixel_size_mm;
  std::optional<double> sample_to_detector_mm;  // NXdetector/distance
  std::optional<double> source_to_sample_mm;    // |NXsource/distance| (NeXus writes it negative: upstream)
  std::vector<std::string> warnings;            // what was assumed (a missing unit, a missing image key)

  /// Frame indices of one kind, in file order.
  std::vector<int> frames_of(NxFrameKind k) const;
};

/// Reads the description (not the frames). `entry` empty: the first group at the root whose
/// `definition` is NXtomo. Throws InputError naming the file and the dataset on anything missing
/// or malformed (the frames' dataset must be 3-D, the keys and angles one per frame).
NxTomo read_nxtomo(const std::filesystem::path& file, const std::string& entry = {});

/// The frames of a described file, read one at a time with the file and its dataset kept open
/// (a scan of thousands of frames opens them once).
class NxTomoFrames {
 public:
  explicit NxTomoFrames(const NxTomo& scan);
  ~NxTomoFrames();
  NxTomoFrames(const NxTomoFrames&) = delete;
  NxTomoFrames& operator=(const NxTomoFrames&) = delete;
  /// One frame as float (integer counts exact up to 2^24). Throws InputError naming the dataset.
  Image read(int frame) const;

 private:
  struct Open;
  const NxTomo& scan_;
  std::unique_ptr<Open> open_;
};

}  // namespace ctk
