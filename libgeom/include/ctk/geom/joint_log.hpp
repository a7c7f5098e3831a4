#pragma once
// joints.csv: header "view,q1,...,q7", one row per reached view, radians (scan-format.md).
// Views may be absent (not reached); out-of-limit rows are flagged, never silently used.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/panda.hpp"

namespace ctk {

struct JointRow {
  int view = 0;
  panda::Joints q{};
  std::string limit_violation;  // empty when all joints are within limits
};

class JointLog {
 public:
  /// Throws InputError (file and line) on a bad header, a non-number, NaN, a duplicate view or
  /// a view outside [0, view_count).
  static JointLog read(const std::filesystem::path& file, int view_count);
  void write(const std::filesystem::path& file) const;

  void add(int view, const panda::Joints& q);
  const std::vector<JointRow>& rows() const { return rows_; }
  /// The row for `view`, or nullptr when the robot did not reach it.
  const JointRow* find(int view) const;

 private:
  std::vector<JointRow> rows_;
  std::vector<int> row_of_view_;  // view -> index into rows_, -1 when absent
};

}  // namespace ctk
