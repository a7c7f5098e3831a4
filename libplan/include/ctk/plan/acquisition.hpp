#pragma once
// How the planner gets a view: it asks for a holder orientation (never for joints: the robot
// stays opaque) and the acquisition side answers with the projection and the joints it logged,
// or with "unreachable". Two sides exist: the simulator (tools) and a lab through files.
//
// The file exchange (folder shared with the acquisition process; formats in libplan/README.md):
//   planner writes  request-NNNN.json  {"format": "ctk-plan-request/1", "view", "direction_holder",
//                                        "R_camera_holder", "holder_origin_camera_mm"}
//   lab writes      answer-NNNN.json   {"format": "ctk-plan-answer/1", "view", "status":
//                                        "acquired" | "unreachable", "projection", "joints_rad", "reason"}
//   and the planner writes "done.json" when the trajectory is complete.
// Both sides write atomically (temporary name, then rename), so a file seen is a file complete.
#include <Eigen/Core>
#include <chrono>
#include <filesystem>
#include <string>

#include "ctk/core/image_io.hpp"
#include "ctk/geom/panda.hpp"

namespace ctk {

struct AcquisitionRequest {
  int view = 0;
  Eigen::Vector3d direction{0, 0, 1};  // beam direction in the holder frame
  Eigen::Matrix3d R_camera_holder = Eigen::Matrix3d::Identity();
  Eigen::Vector3d holder_origin_camera_mm{0, 0, 0};  // where the holder origin should be
};

struct AcquisitionAnswer {
  bool acquired = false;
  std::string reason;  // why not, when not
  panda::Joints joints{};
  Image counts;                 // raw detector counts
  std::string projection_file;  // where the image is (relative to the exchange folder), if a file
};

class Acquisition {
 public:
  virtual ~Acquisition() = default;
  virtual AcquisitionAnswer acquire(const AcquisitionRequest& request) = 0;
};

class FileExchangeAcquisition final : public Acquisition {
 public:
  /// `detector_cols/rows`: the size every answered projection must have.
  FileExchangeAcquisition(std::filesystem::path folder, int detector_cols, int detector_rows,
                          std::chrono::seconds timeout = std::chrono::seconds(600));
  /// Throws InputError naming the answer file and key when it is malformed, and std::runtime_error
  /// when no answer arrives within the timeout.
  AcquisitionAnswer acquire(const AcquisitionRequest& request) override;
  void finish();  // writes done.json

 private:
  std::filesystem::path folder_;
  int cols_, rows_;
  std::chrono::seconds timeout_;
};

std::filesystem::path request_file(const std::filesystem::path& folder, int view);
std::filesystem::path answer_file(const std::filesystem::path& folder, int view);
/// The lab side's helpers: read a request, write an answer (atomically).
AcquisitionRequest read_request(const std::filesystem::path& file);
void write_answer(const std::filesystem::path& folder, int view, const AcquisitionAnswer& answer);

}  // namespace ctk
