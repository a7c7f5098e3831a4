#include "ctk/plan/acquisition.hpp"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/provenance.hpp"

namespace ctk {

namespace {

std::string numbered(const char* stem, int view) {
  char name[64];
  std::snprintf(name, sizeof name, "%s-%04d.json", stem, view);
  return name;
}

nlohmann::json json3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

std::filesystem::path request_file(const std::filesystem::path& folder, int view) { return folder / numbered("request", view); }
std::filesystem::path answer_file(const std::filesystem::path& folder, int view) { return folder / numbered("answer", view); }

FileExchangeAcquisition::FileExchangeAcquisition(std::filesystem::path folder, int cols, int rows, std::chrono::seconds timeout)
    : folder_(std::move(folder)), cols_(cols), rows_(rows), timeout_(timeout) {
  std::filesystem::create_directories(folder_);
}

AcquisitionAnswer FileExchangeAcquisition::acquire(const AcquisitionRequest& r) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) rows.push_back(json3(r.R_camera_holder.row(i).transpose()));
  const nlohmann::json request = {{"format", "ctk-plan-request/1"},
                                  {"provenance", provenance()},
                                  {"view", r.view},
                                  {"direction_holder", json3(r.direction)},
                                  {"R_camera_holder", rows},
                                  {"holder_origin_camera_mm", json3(r.holder_origin_camera_mm)}};
  const std::filesystem::path file = answer_file(folder_, r.view), asked = request_file(folder_, r.view);
  // An answer already here is from an earlier run in this folder, stopped before the end. It is
  // taken when it answered the same direction, so the same command run again replays the views
  // the lab has acquired (the planner is deterministic for a seed) and goes on from there; an
  // answer to another direction is an error, never mixed in.
  if (std::filesystem::exists(file) && std::filesystem::exists(asked)) {
    const Eigen::Vector3d earlier = read_request(asked).direction;
    if ((earlier - r.direction).norm() > 1e-9) {
      std::ostringstream what;
      what << "answers a request of an earlier run for direction (" << earlier.transpose() << "), but view " << r.view
           << " now asks for (" << r.direction.transpose()
           << "): run with the earlier run's settings, or give a folder without its answers";
      throw InputError(file.string(), "view", what.str());
    }
  } else if (std::filesystem::exists(file)) {
    // An answer whose request is gone cannot be told to answer this direction: it is stale.
    throw InputError(file.string(), "view",
                     "an answer without its request " + asked.filename().string() +
                         " (left by another run?): remove it, or give a folder without it");
  } else {
    write_text_atomically(asked, request.dump(2) + "\n");
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout_;
  while (!std::filesystem::exists(file)) {
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("no answer " + file.string() + " within " + std::to_string(timeout_.count()) + " s");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const nlohmann::json json = read_json_file(file);
  const JsonNode root(json, file.string(), "");
  if (root.at("format").string() != "ctk-plan-answer/1") root.at("format").fail("expected \"ctk-plan-answer/1\"");
  if (root.at("view").integer() != r.view) root.at("view").fail("expected " + std::to_string(r.view));
  AcquisitionAnswer a;
  const std::string status = root.at("status").string();
  if (status == "unreachable") {
    if (auto reason = root.find("reason")) a.reason = reason->string();
    return a;
  }
  if (status != "acquired") root.at("status").fail("expected \"acquired\" or \"unreachable\", got \"" + status + "\"");
  a.acquired = true;
  const std::vector<double> q = root.at("joints_rad").numbers(7);
  for (std::size_t j = 0; j < 7; ++j) a.joints[j] = q[j];
  a.projection_file = root.at("projection").string();
  a.counts = read_image(folder_ / a.projection_file, cols_, rows_);
  return a;
}

void FileExchangeAcquisition::finish() {
  write_text_atomically(folder_ / "done.json",
                        nlohmann::json{{"format", "ctk-plan-done/1"}, {"provenance", provenance()}}.dump() + "\n");
}

AcquisitionRequest read_request(const std::filesystem::path& file) {
  const nlohmann::json json = read_json_file(file);
  const JsonNode root(json, file.string(), "");
  if (root.at("format").string() != "ctk-plan-request/1") root.at("format").fail("expected \"ctk-plan-request/1\"");
  AcquisitionRequest r;
  r.view = root.at("view").integer();
  r.direction = root.at("direction_holder").vector3();
  r.R_camera_holder = root.at("R_camera_holder").matrix3();
  r.holder_origin_camera_mm = root.at("holder_origin_camera_mm").vector3();
  return r;
}

void write_answer(const std::filesystem::path& folder, int view, const AcquisitionAnswer& a) {
  nlohmann::json j = {{"format", "ctk-plan-answer/1"}, {"view", view}, {"status", a.acquired ? "acquired" : "unreachable"}};
  if (a.acquired) {
    j["projection"] = a.projection_file;
    j["joints_rad"] = std::vector<double>(a.joints.begin(), a.joints.end());
  } else {
    j["reason"] = a.reason;
  }
  write_text_atomically(answer_file(folder, view), j.dump(2) + "\n");
}

}  // namespace ctk
