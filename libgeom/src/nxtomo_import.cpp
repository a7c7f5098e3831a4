#include "ctk/geom/nxtomo_import.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "ctk/core/cancellation.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

double required(const std::optional<double>& given, const std::optional<double>& in_file, const NxTomo& scan,
                const std::string& dataset, const std::string& option, std::vector<std::string>& notes) {
  if (given) return *given;
  if (in_file) {
    std::ostringstream s;
    s << dataset << ": " << *in_file << " mm";
    notes.push_back(s.str());
    return *in_file;
  }
  throw InputError(scan.file.string(), "dataset '" + scan.entry + "/" + dataset + "'",
                   "missing (or without a length unit): give " + option);
}

// Every pixel a whole number within 16 bits: such frames stay 16-bit counts.
bool fits_16_bits(const Image& image) {
  return std::all_of(image.pixels.begin(), image.pixels.end(),
                     [](float p) { return p >= 0 && p <= 65535 && p == std::floor(p); });
}

}  // namespace

NxTomoPlan plan_nxtomo_import(const NxTomo& scan, const NxTomoSetup& setup) {
  NxTomoPlan plan;
  plan.projections = scan.frames_of(NxFrameKind::projection);
  plan.flats = scan.frames_of(NxFrameKind::flat);
  plan.darks = scan.frames_of(NxFrameKind::dark);
  plan.notes = scan.warnings;
  if (plan.projections.empty())
    throw InputError(scan.file.string(), "dataset '" + scan.entry + "/instrument/detector/image_key'",
                     "no frame has key 0 (projection)");
  plan.line_integrals = setup.line_integrals;
  if (!plan.line_integrals && plan.flats.empty())
    throw InputError(scan.file.string(), "dataset '" + scan.entry + "/instrument/detector/image_key'",
                     "no flat frame (key 1) to turn counts into line integrals (frames that are line integrals already: --kind "
                     "line_integrals)");
  if (!plan.line_integrals && plan.darks.empty()) plan.notes.push_back("no dark frame (key 2): the dark is taken as 0 counts");

  const double sod =
      required(setup.source_to_axis_mm, scan.source_to_sample_mm, scan, "instrument/source/distance", "--sod", plan.notes);
  double sdd = 0;
  if (setup.source_to_detector_mm) {
    sdd = *setup.source_to_detector_mm;
  } else {
    sdd = sod + required(std::nullopt, scan.sample_to_detector_mm, scan, "instrument/detector/distance", "--sdd", plan.notes);
  }
  const double pu = setup.pitch_mm ? setup.pitch_mm->x()
                                   : required(std::nullopt, scan.x_pixel_size_mm, scan, "instrument/detector/x_pixel_size",
                                              "--pitch", plan.notes);
  const double pv = setup.pitch_mm ? setup.pitch_mm->y()
                                   : required(std::nullopt, scan.y_pixel_size_mm, scan, "instrument/detector/y_pixel_size",
                                              "--pitch", plan.notes);
  CircularOrbit& o = plan.orbit;
  o.detector = Detector{scan.cols, scan.rows, pu, pv};
  o.principal_point_px = setup.principal_point_px.value_or(o.detector.centre_px());
  o.source_to_axis_mm = sod;
  o.source_to_detector_mm = sdd;
  o.sense = setup.sense;
  // NeXus' McStas frame against ctk's orbit: at angle 0 both put the source on the beam upstream of
  // the axis with columns along the same horizontal, and both turn the sample right-handed about up.
  for (int f : plan.projections) o.angles_rad.push_back(scan.rotation_angle_deg[static_cast<std::size_t>(f)] * M_PI / 180.0);
  return plan;
}

ImportedScan import_nxtomo(const NxTomo& scan, const NxTomoPlan& plan, const fs::path& scan_file,
                           const std::function<void(int, int)>& progress) {
  // The matrices before any frame is copied: numbers that describe no projection are refused first.
  std::vector<ProjectionMatrix> matrices;
  try {
    matrices = circular_matrices(plan.orbit);
  } catch (const std::invalid_argument& e) {
    throw InputError(scan.file.string(),
                     "entry '" + scan.entry +
                         "' (instrument/detector/x_pixel_size, y_pixel_size and distance, instrument/source/distance, or the "
                         "values given for them)",
                     e.what());
  }
  const fs::path folder = fs::absolute(scan_file).parent_path() / (fs::path(scan_file).stem().string() + ".frames");
  const int total = static_cast<int>(plan.projections.size() + plan.flats.size() + plan.darks.size());
  int written = 0;
  const NxTomoFrames frames(scan);
  // The frames are written into a hidden folder beside their folder and put in its place in one
  // step when the run publishes its scan (a stop before then leaves nothing): a kill leaves the earlier import's frames whole
  // (the next import removes what it left), never two imports' frames mixed under one scan.json. Everything in the folder is the
  // import's: an earlier import's frames go as a whole. The frames name this run, as the scan does, so that frames and a scan of
  // different runs are refused by the readers.
  std::vector<std::string> earlier;
  std::error_code absent;
  for (fs::directory_iterator it(folder, absent), end; !absent && it != end; it.increment(absent))
    earlier.push_back(it->path().filename().string());
  auto staged = std::make_unique<StagedFolder>(folder, earlier);
  auto write = [&](const Image& image, const std::string& name, bool counts) {
    const OutputSet::Outside at_once;  // written into the hidden folder now, not held for the run's outputs
    if (counts)
      write_image_uint16(image, staged->path() / name);
    else
      write_image_float(image, staged->path() / name);
    return (folder / name).string();
  };
  auto copy = [&](int frame, const std::string& name) {
    const Image image = frames.read(frame);
    std::string file = write(image, name, scan.integer_data && fits_16_bits(image));
    if (progress) progress(++written, total);
    throw_if_stop_requested();  // a caller's stop (Python's Ctrl-C) between frames
    return file;
  };
  auto numbered = [](const char* stem, std::size_t i) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%s_%05zu.tif", stem, i);
    return std::string(buffer);
  };
  ProjectionSet set;
  set.count = static_cast<int>(plan.projections.size());
  for (std::size_t i = 0; i < plan.projections.size(); ++i)
    set.file_names.push_back(copy(plan.projections[i], numbered("proj", i)));
  if (!plan.line_integrals) {
    set.kind = ProjectionKind::counts;
    for (std::size_t i = 0; i < plan.flats.size(); ++i) set.flat.push_back(copy(plan.flats[i], numbered("flat", i)));
    for (std::size_t i = 0; i < plan.darks.size(); ++i) set.dark.push_back(copy(plan.darks[i], numbered("dark", i)));
    if (plan.darks.empty()) {
      const Image zero{scan.cols, scan.rows,
                       std::vector<float>(static_cast<std::size_t>(scan.cols) * static_cast<std::size_t>(scan.rows), 0.0f)};
      set.dark.push_back(write(zero, "dark_zero.tif", true));
    }
  }
  commit_with_outputs(std::move(staged));  // with the matrices and the scan that name the frames
  ImportedScan imported = import_matrices(plan.orbit.detector, matrices, set, scan_file);
  imported.scan.written_by_run = this_run_id();
  return imported;
}

}  // namespace ctk
