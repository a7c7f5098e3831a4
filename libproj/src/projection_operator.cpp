#include "ctk/proj/projection_operator.hpp"

#include <stdexcept>
#include <string>

namespace ctk {

namespace {

std::string shape_text(const StackShape& s) {
  return std::to_string(s.views) + " x " + std::to_string(s.rows) + " x " + std::to_string(s.cols);
}

std::string layout_text(const VolumeLayout& l) {
  return std::to_string(l.size[0]) + " x " + std::to_string(l.size[1]) + " x " + std::to_string(l.size[2]);
}

void require_domain(const VolumeLayout& given, const VolumeLayout& domain, const char* what) {
  if (!(given == domain))
    throw std::invalid_argument(std::string("projection operator: the ") + what + " (" + layout_text(given) +
                                " voxels) does not have the operator's layout (" + layout_text(domain) +
                                " voxels, same voxel size and origin)");
}

void require_range(const StackShape& given, const StackShape& range, const char* what) {
  if (!(given == range))
    throw std::invalid_argument(std::string("projection operator: the ") + what + " (" + shape_text(given) +
                                ") do not have the operator's shape (" + shape_text(range) + ", views x rows x cols)");
}

}  // namespace

void ProjectionOperator::apply(ConstVolumeSpan x, StackSpan y) const {
  require_domain(x.layout, domain(), "volume");
  require_range({y.views, y.rows, y.cols}, range(), "projections to fill");
  do_apply(x, y);
}

void ProjectionOperator::apply(ConstVolumeSpan x, ProjectionStack& y) const {
  require_domain(x.layout, domain(), "volume");
  const StackShape r = range();
  if (!(StackShape::of(y) == r) || y.data.size() != static_cast<std::size_t>(r.views) * y.pixels_per_view())
    y = ProjectionStack(r.views, r.rows, r.cols);
  do_apply(x, y);
}

void ProjectionOperator::apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  require_range({y.views, y.rows, y.cols}, range(), "projections");
  require_domain(x.layout, domain(), "volume to fill");
  do_apply_adjoint(y, x);
}

void ProjectionOperator::apply_adjoint(ConstStackSpan y, Volume& x) const {
  require_range({y.views, y.rows, y.cols}, range(), "projections");
  if (!(x.layout == domain()) || x.data.size() != domain().voxel_count()) x = Volume(domain());
  do_apply_adjoint(y, x);
}

ProjectionStack ProjectionOperator::range_zeros() const {
  const StackShape r = range();
  return ProjectionStack(r.views, r.rows, r.cols);
}

Volume ProjectionOperator::domain_zeros() const { return Volume(domain()); }

void ProjectionOperator::check_subset(const std::vector<int>& views) const {
  const int n = range().views;
  for (int v : views)
    if (v < 0 || v >= n)
      throw std::out_of_range("projection operator: view " + std::to_string(v) + " of a subset is outside 0.." +
                              std::to_string(n - 1));
}

}  // namespace ctk
