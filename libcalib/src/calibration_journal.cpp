#include "ctk/calib/calibration_journal.hpp"

#include <stdexcept>
#include <string>

#include "ctk/core/error.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/provenance.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "ctk-calibration-journal/1";

nlohmann::json points(const std::vector<Eigen::Vector2d>& p) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& x : p) out.push_back({x.x(), x.y()});
  return out;
}

std::vector<Eigen::Vector2d> points_from(const JsonNode& node) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const auto p = node.at(i).numbers(2);
    out.emplace_back(p[0], p[1]);
  }
  return out;
}

std::vector<int> integers_from(const JsonNode& node) {
  std::vector<int> out;
  for (std::size_t i = 0; i < node.size(); ++i) out.push_back(node.at(i).integer());
  return out;
}

}  // namespace

nlohmann::json view_calibration_to_json(const ViewCalibration& v) {
  nlohmann::json j = {{"status", to_string(v.status)},
                      {"reason", v.reason},
                      {"rms_px", v.rms_px},
                      {"spheres_used", v.spheres_used},
                      {"detections", v.detections},
                      {"radius_px", v.radius_px},
                      {"translation_sigma_mm", {v.translation_sigma_mm[0], v.translation_sigma_mm[1], v.translation_sigma_mm[2]}},
                      {"rotation_sigma_deg", v.rotation_sigma_deg},
                      {"detected_px", points(v.detected_px)},
                      {"fitted_px", points(v.fitted_px)},
                      {"spheres", v.spheres},
                      {"outlier_spheres", v.outlier_spheres},
                      {"outlier_detected_px", points(v.outlier_detected_px)},
                      {"residual_decides", v.residual_decides}};
  if (v.P) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 3; ++r)
      rows.push_back({v.P->matrix()(r, 0), v.P->matrix()(r, 1), v.P->matrix()(r, 2), v.P->matrix()(r, 3)});
    j["P"] = rows;
  }
  if (v.T_camera_holder) j["T_camera_holder"] = rigid_to_json(*v.T_camera_holder);
  return j;
}

ViewCalibration view_calibration_from_json(const nlohmann::json& json, const std::string& file, const std::string& path) {
  const JsonNode node(json, file, path);
  ViewCalibration v;
  const std::string status = node.at("status").string();
  if (status == "ok")
    v.status = ViewStatus::ok;
  else if (status == "rejected")
    v.status = ViewStatus::rejected;
  else if (status == "skipped")
    v.status = ViewStatus::skipped;
  else
    node.at("status").fail("expected ok, rejected or skipped");
  v.reason = node.at("reason").string();
  v.rms_px = node.at("rms_px").number();
  v.spheres_used = node.at("spheres_used").integer();
  v.detections = node.at("detections").integer();
  v.radius_px = node.at("radius_px").number();
  const auto sigma = node.at("translation_sigma_mm").numbers(3);
  for (int a = 0; a < 3; ++a) v.translation_sigma_mm[a] = sigma[static_cast<std::size_t>(a)];
  v.rotation_sigma_deg = node.at("rotation_sigma_deg").number();
  v.detected_px = points_from(node.at("detected_px"));
  v.fitted_px = points_from(node.at("fitted_px"));
  v.spheres = integers_from(node.at("spheres"));
  v.outlier_spheres = integers_from(node.at("outlier_spheres"));
  v.outlier_detected_px = points_from(node.at("outlier_detected_px"));
  if (auto decides = node.find("residual_decides")) v.residual_decides = decides->boolean();
  if (auto P = node.find("P")) {
    Matrix34d m;
    for (int r = 0; r < 3; ++r) {
      const auto row = P->at(static_cast<std::size_t>(r)).numbers(4);
      for (int c = 0; c < 4; ++c) m(r, c) = row[static_cast<std::size_t>(c)];
    }
    try {
      v.P = ProjectionMatrix(m);
    } catch (const std::invalid_argument& e) {
      P->fail(e.what());
    }
  }
  if (auto T = node.find("T_camera_holder")) v.T_camera_holder = rigid_from_json(*T);
  return v;
}

CalibrationJournal::CalibrationJournal(fs::path file, const nlohmann::json& run) : file_(std::move(file)) {
  if (file_.has_parent_path()) fs::create_directories(file_.parent_path());
  out_.open(file_, std::ios::trunc);
  if (!out_) throw std::runtime_error(file_.string() + ": cannot write the calibration journal");
  out_ << nlohmann::json({{"format", kFormat}, {"provenance", provenance()}, {"run", run}}).dump() << "\n" << std::flush;
}

std::unique_ptr<CalibrationJournal> CalibrationJournal::resume(const fs::path& file, const nlohmann::json& run) {
  require_regular_file(file);
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line)) throw InputError(file.string(), "", "an empty calibration journal");
  nlohmann::json head;
  try {
    head = nlohmann::json::parse(line);
  } catch (const nlohmann::json::exception&) {
    throw InputError(file.string(), "", "not a calibration journal (its first line is not JSON)");
  }
  const JsonNode top(head, file.string(), "");
  if (!head.is_object() || top.at("format").string() != kFormat) top.fail(std::string("not a ") + kFormat + " file");
  require_same_run(top.at("run").raw(), run, file.string(), "run",
                   "continue with the same scan and options, or start afresh without --resume");
  std::unique_ptr<CalibrationJournal> journal(new CalibrationJournal);
  journal->file_ = file;
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    nlohmann::json entry;
    try {
      entry = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception&) {
      if (in.peek() == std::char_traits<char>::eof()) break;  // the line a kill cut short
      throw InputError(file.string(), "line " + std::to_string(line_number), "is not JSON (a damaged journal)");
    }
    const std::string where = "line " + std::to_string(line_number);
    const JsonNode node(entry, file.string(), where);
    const int view = node.at("view").integer();
    journal->done_[view] = view_calibration_from_json(entry.at("result"), file.string(), where + ": result");
  }
  journal->out_.open(file, std::ios::app);
  if (!journal->out_) throw std::runtime_error(file.string() + ": cannot append to the calibration journal");
  return journal;
}

void CalibrationJournal::record(int view, const ViewCalibration& result) {
  const std::string line = nlohmann::json({{"view", view}, {"result", view_calibration_to_json(result)}}).dump();
  const std::lock_guard lock(mutex_);
  out_ << line << "\n" << std::flush;
  done_[view] = result;
}

void CalibrationJournal::remove() {
  out_.close();
  std::error_code ignored;
  fs::remove(file_, ignored);
}

}  // namespace ctk
