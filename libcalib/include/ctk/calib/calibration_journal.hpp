#pragma once
// The views a calibration has finished, one JSON line each, appended and flushed as each view
// completes: a run stopped by Ctrl-C or killed outright leaves every finished view behind, and
// `ctk calibrate --resume` takes them as they are and calibrates only the rest. The first line
// says which run (scan, options) the views belong to; a last line cut short by a kill is ignored.
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>

#include "ctk/calib/view_calibration.hpp"

namespace ctk {

nlohmann::json view_calibration_to_json(const ViewCalibration& view);
/// Throws InputError naming `file` and the key.
ViewCalibration view_calibration_from_json(const nlohmann::json& json, const std::string& file, const std::string& path);

class CalibrationJournal {
 public:
  /// Starts a journal at `file` for the run `run` (replacing any earlier one).
  CalibrationJournal(std::filesystem::path file, const nlohmann::json& run);
  /// Continues the journal at `file`: its run must equal `run` (InputError naming the first key
  /// that differs); the views it holds are in done().
  static std::unique_ptr<CalibrationJournal> resume(const std::filesystem::path& file, const nlohmann::json& run);

  const std::map<int, ViewCalibration>& done() const { return done_; }
  /// Appends one finished view and flushes it to the file; safe from several threads.
  void record(int view, const ViewCalibration& result);
  /// The run completed: the journal is no longer needed.
  void remove();

 private:
  CalibrationJournal() = default;
  std::filesystem::path file_;
  std::ofstream out_;
  std::mutex mutex_;
  std::map<int, ViewCalibration> done_;
};

}  // namespace ctk
