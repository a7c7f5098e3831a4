#include "ctk/proj/slab_split_operator.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace ctk {

RowRange RowRange::intersection(const RowRange& o) const {
  const int a = std::max(first, o.first), b = std::min(end(), o.end());
  return b > a ? RowRange{a, b - a} : RowRange{a, 0};
}

RowRange slab_planes(int planes, int rank, int ranks) {
  if (ranks < 1 || rank < 0 || rank >= ranks) throw std::invalid_argument("slab_planes: rank outside 0 .. ranks - 1");
  const int base = planes / ranks, extra = planes % ranks;
  return {rank * base + std::min(rank, extra), base + (rank < extra ? 1 : 0)};
}

VolumeLayout slab_layout(const VolumeLayout& whole, int rank, int ranks) {
  const RowRange planes = slab_planes(whole.size[2], rank, ranks);
  VolumeLayout slab = whole;
  slab.size[2] = planes.count;
  slab.origin_mm.z() += planes.first * whole.voxel_mm.z();
  return slab;
}

namespace {

// The rows a slab reaches: its box (voxel centres widened by one voxel, where the interpolation
// still reads them) seen from the view, with a row's margin, on the detector.
RowRange footprint_of(const ProjectionMatrix& P, const VolumeLayout& slab, int detector_rows) {
  if (slab.size[2] == 0) return {0, 0};
  const Eigen::Vector3d low = slab.origin_mm - slab.voxel_mm;
  const Eigen::Vector3d high =
      slab.origin_mm + Eigen::Vector3d(slab.size[0], slab.size[1], slab.size[2]).cwiseProduct(slab.voxel_mm);
  double v_min = 1e300, v_max = -1e300;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d X(corner & 1 ? high.x() : low.x(), corner & 2 ? high.y() : low.y(), corner & 4 ? high.z() : low.z());
    const double v = P.project(X).y();
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  const int first = std::max(0, static_cast<int>(std::floor(v_min)) - 1);
  const int end = std::min(detector_rows, static_cast<int>(std::ceil(v_max)) + 2);
  return end > first ? RowRange{first, end - first} : RowRange{0, 0};
}

}  // namespace

SlabRows::SlabRows(const std::vector<ProjectionMatrix>& views, const VolumeLayout& whole, int detector_rows, int ranks)
    : ranks_(ranks) {
  if (ranks < 1) throw std::invalid_argument("SlabRows: ranks must be at least 1");
  for (const ProjectionMatrix& P : views) {
    std::vector<RowRange> reach, own(static_cast<std::size_t>(ranks));
    for (int q = 0; q < ranks; ++q) reach.push_back(footprint_of(P, slab_layout(whole, q, ranks), detector_rows));
    // The ranks that reach the detector, in the order of their footprints' centres; each owns
    // the rows up to the midpoint between its centre and the next one's.
    std::vector<int> order;
    for (int q = 0; q < ranks; ++q)
      if (reach[static_cast<std::size_t>(q)].count > 0) order.push_back(q);
    const auto centre = [&](int q) {
      return reach[static_cast<std::size_t>(q)].first + 0.5 * reach[static_cast<std::size_t>(q)].count;
    };
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return centre(a) < centre(b); });
    if (order.empty()) order.push_back(0);  // nothing reaches the detector: one rank owns every row
    int start = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const int end =
          k + 1 < order.size()
              ? std::clamp(static_cast<int>(std::lround(0.5 * (centre(order[k]) + centre(order[k + 1])))), start, detector_rows)
              : detector_rows;
      own[static_cast<std::size_t>(order[k])] = {start, end - start};
      start = end;
    }
    footprint_.push_back(std::move(reach));
    owned_.push_back(std::move(own));
  }
}

const RowRange& SlabRows::footprint(int view, int rank) const {
  return footprint_.at(static_cast<std::size_t>(view)).at(static_cast<std::size_t>(rank));
}
const RowRange& SlabRows::owned(int view, int rank) const {
  return owned_.at(static_cast<std::size_t>(view)).at(static_cast<std::size_t>(rank));
}

int SlabRows::owned_height(int rank) const {
  int h = 0;
  for (int v = 0; v < views(); ++v) h = std::max(h, owned(v, rank).count);
  return h;
}

int SlabRows::footprint_height(int rank) const {
  int h = 0;
  for (int v = 0; v < views(); ++v) h = std::max(h, footprint(v, rank).count);
  return h;
}

std::size_t SlabRows::exchanged_rows(int rank) const {
  std::size_t rows = 0;
  for (int v = 0; v < views(); ++v)
    for (int q = 0; q < ranks_; ++q)
      if (q != rank)
        rows += static_cast<std::size_t>(footprint(v, rank).intersection(owned(v, q)).count +
                                         owned(v, rank).intersection(footprint(v, q)).count);
  return rows;
}

SlabSplitOperator::SlabSplitOperator(std::vector<ProjectionMatrix> views, const VolumeLayout& whole, int detector_rows,
                                     int detector_cols, std::shared_ptr<const SlabRows> rows, const Communicator& ranks,
                                     const ProjectorOptions& options)
    : all_views_(std::move(views)),
      slab_(slab_layout(whole, ranks.rank(), ranks.size())),
      detector_rows_(detector_rows),
      cols_(detector_cols),
      rows_(std::move(rows)),
      ranks_(ranks),
      projector_(options) {
  if (!rows_ || rows_->views() != static_cast<int>(all_views_.size()) || rows_->ranks() != ranks.size())
    throw std::invalid_argument("SlabSplitOperator: the rows were not computed for these views and ranks");
  if (slab_.size[2] < 1)
    throw std::invalid_argument("SlabSplitOperator: " + std::to_string(ranks.size()) + " ranks for " +
                                std::to_string(whole.size[2]) + " planes leave a rank without a plane");
  view_ids_.resize(all_views_.size());
  std::iota(view_ids_.begin(), view_ids_.end(), 0);
  height_ = std::max(1, rows_->owned_height(ranks.rank()));
  band_height_ = std::max(1, rows_->footprint_height(ranks.rank()));
}

SlabSplitOperator::SlabSplitOperator(const SlabSplitOperator& parent, std::vector<int> view_ids)
    : all_views_(parent.all_views_),
      view_ids_(std::move(view_ids)),
      slab_(parent.slab_),
      detector_rows_(parent.detector_rows_),
      cols_(parent.cols_),
      height_(parent.height_),
      band_height_(parent.band_height_),
      rows_(parent.rows_),
      ranks_(parent.ranks_),
      projector_(parent.projector_) {}

std::shared_ptr<const ProjectionOperator> SlabSplitOperator::subset(const std::vector<int>& views) const {
  check_subset(views);
  std::vector<int> ids;
  ids.reserve(views.size());
  for (int v : views) ids.push_back(view_ids_[static_cast<std::size_t>(v)]);
  return std::shared_ptr<const ProjectionOperator>(new SlabSplitOperator(*this, std::move(ids)));
}

ProjectionStack& SlabSplitOperator::band_buffer() const {
  if (band_.views != static_cast<int>(view_ids_.size()))
    band_ = ProjectionStack(static_cast<int>(view_ids_.size()), band_height_, cols_);
  return band_;
}

std::vector<ProjectionMatrix> SlabSplitOperator::band_matrices() const {
  std::vector<ProjectionMatrix> out;
  for (int id : view_ids_) {
    Matrix34d P = all_views_[static_cast<std::size_t>(id)].matrix();
    P.row(1) -= rows_->footprint(id, ranks_.rank()).first * P.row(2);  // v' = v - first row
    out.emplace_back(P);
  }
  return out;
}

std::vector<std::vector<float>> SlabSplitOperator::rows_for_each_rank(const std::function<const float*(int)>& view, RowsOf held,
                                                                      RowsOf wanted) const {
  const int me = ranks_.rank();
  const std::size_t row = static_cast<std::size_t>(cols_);
  std::vector<std::vector<float>> to(static_cast<std::size_t>(ranks_.size()));
  for (int q = 0; q < ranks_.size(); ++q)
    for (std::size_t k = 0; k < view_ids_.size() && q != me; ++k) {  // this rank's own rows stay where they are
      const RowRange mine = (*rows_.*held)(view_ids_[k], me), shared = mine.intersection((*rows_.*wanted)(view_ids_[k], q));
      const float* from = view(static_cast<int>(k)) + static_cast<std::size_t>(shared.first - mine.first) * row;
      to[static_cast<std::size_t>(q)].insert(to[static_cast<std::size_t>(q)].end(), from,
                                             from + static_cast<std::size_t>(shared.count) * row);
    }
  return to;
}

void SlabSplitOperator::do_apply(ConstVolumeSpan x, StackSpan y) const {
  const int me = ranks_.rank(), n = ranks_.size();
  const std::size_t row = static_cast<std::size_t>(cols_);
  ProjectionStack& band = band_buffer();
  projector_.forward(x, band_matrices(), band);
  // To each owner, the rows of every view this slab reaches and it owns.
  const std::vector<std::vector<float>> from = ranks_.exchange(
      rows_for_each_rank([&](int k) { return static_cast<const float*>(band.view(k)); }, &SlabRows::footprint, &SlabRows::owned));
  // Each owned row: the ranks' parts added in rank order.
  std::fill_n(y.data, static_cast<std::size_t>(y.views) * static_cast<std::size_t>(y.rows) * row, 0.0f);
  for (int q = 0; q < n; ++q) {
    const float* part = from[static_cast<std::size_t>(q)].data();
    for (std::size_t k = 0; k < view_ids_.size(); ++k) {
      const RowRange owned = rows_->owned(view_ids_[k], me), reach = rows_->footprint(view_ids_[k], q),
                     shared = reach.intersection(owned);
      float* out = y.view(static_cast<int>(k)) + static_cast<std::size_t>(shared.first - owned.first) * row;
      const std::size_t values = static_cast<std::size_t>(shared.count) * row;
      const float* in =
          q == me ? band.view(static_cast<int>(k)) + static_cast<std::size_t>(shared.first - reach.first) * row : part;
      for (std::size_t i = 0; i < values; ++i) out[i] += in[i];
      if (q != me) part += values;
    }
  }
}

void SlabSplitOperator::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  const int me = ranks_.rank(), n = ranks_.size();
  const std::size_t row = static_cast<std::size_t>(cols_);
  // To each rank, the rows of every view this rank owns and that rank's slab reaches.
  const std::vector<std::vector<float>> from =
      ranks_.exchange(rows_for_each_rank([&](int k) { return y.view(k); }, &SlabRows::owned, &SlabRows::footprint));
  ProjectionStack& band = band_buffer();
  std::fill(band.data.begin(), band.data.end(), 0.0f);
  for (int q = 0; q < n; ++q) {
    const float* part = from[static_cast<std::size_t>(q)].data();
    for (std::size_t k = 0; k < view_ids_.size(); ++k) {
      const RowRange mine = rows_->footprint(view_ids_[k], me), owned = rows_->owned(view_ids_[k], q),
                     shared = owned.intersection(mine);
      const std::size_t values = static_cast<std::size_t>(shared.count) * row;
      const float* in = q == me ? y.view(static_cast<int>(k)) + static_cast<std::size_t>(shared.first - owned.first) * row : part;
      std::copy_n(in, values, band.view(static_cast<int>(k)) + static_cast<std::size_t>(shared.first - mine.first) * row);
      if (q != me) part += values;
    }
  }
  projector_.back(band, band_matrices(), x);
}

}  // namespace ctk
