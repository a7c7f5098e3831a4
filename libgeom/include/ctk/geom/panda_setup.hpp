#pragma once
// A robot CT setup: source and detector fixed, a Panda holding the holder between them. The
// reference setup places the robot so that, in its "ready" pose, the holder centre sits on the
// principal ray at the source-to-isocentre distance with its axis perpendicular to the beam;
// spinning joint 7 then turns the holder about its own axis (a circular trajectory).
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/panda.hpp"
#include "ctk/geom/rigid.hpp"

namespace ctk {

struct PandaSetup {
  Detector detector;
  Eigen::Vector2d principal_point_px{0, 0};
  double source_to_detector_mm = 0;
  double source_to_isocentre_mm = 0;
  Rigid T_camera_base = Rigid::Identity();
  Rigid T_flange_holder = Rigid::Identity();
  panda::Joints ready{};
};

/// Ready pose (0, -pi/4, 0, -3pi/4, 0, pi/2, pi/4): flange pointing down; holder centre
/// `holder_offset_mm` beyond the flange on its axis; beam horizontal along the base's +y.
PandaSetup reference_panda_setup(const Detector& detector, double source_to_detector_mm, double source_to_isocentre_mm,
                                 double holder_offset_mm = 150.0);

/// `count` joint vectors from the ready pose with joint 7 stepped evenly over its whole range
/// (332 degrees: one joint cannot turn a full circle).
std::vector<panda::Joints> joint7_orbit(const PandaSetup& setup, int count);

}  // namespace ctk
