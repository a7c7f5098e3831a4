// Runs spread over ranks, with the ranks played by threads of this process so the test needs no
// MPI: views dealt to the ranks with the whole volume on each (view_split_operator.hpp), and the
// volume split into slabs with each view's rows split over the ranks (slab_split_operator.hpp).
// Both are adjoint pairs across the ranks, and the solvers on them give the single-process
// result. The same runs over real MPI ranks are cli.mpi_runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <cmath>
#include <random>
#include <stdexcept>
#include <thread>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/slab_split_operator.hpp"
#include "ctk/proj/view_split_operator.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

// Ranks as threads: every collective waits for all of them at a barrier, then each adds up the
// others' arrays in rank order.
class ThreadRanks {
 public:
  explicit ThreadRanks(int n)
      : barrier_(n),
        floats_(static_cast<std::size_t>(n)),
        doubles_(static_cast<std::size_t>(n)),
        texts_(static_cast<std::size_t>(n)),
        outboxes_(static_cast<std::size_t>(n)) {
    for (int r = 0; r < n; ++r) ranks_.emplace_back(*this, r);
  }
  const Communicator& rank(int r) const { return ranks_[static_cast<std::size_t>(r)]; }
  int size() const { return static_cast<int>(ranks_.size()); }

 private:
  class Rank final : public Communicator {
   public:
    Rank(ThreadRanks& all, int rank) : all_(all), rank_(rank) {}
    int rank() const override { return rank_; }
    int size() const override { return all_.size(); }
    using Communicator::sum;
    void sum(std::span<float> values) const override { all_.sum(all_.floats_, rank_, values); }
    void sum(std::span<double> values) const override { all_.sum(all_.doubles_, rank_, values); }
    std::vector<std::string> gather(const std::string& text) const override {
      all_.texts_[static_cast<std::size_t>(rank_)] = text;
      all_.barrier_.arrive_and_wait();
      std::vector<std::string> out = all_.texts_;
      all_.barrier_.arrive_and_wait();
      return out;
    }
    std::vector<std::vector<float>> exchange(std::vector<std::vector<float>> to) const override {
      all_.outboxes_[static_cast<std::size_t>(rank_)] = std::move(to);
      all_.barrier_.arrive_and_wait();
      std::vector<std::vector<float>> from;
      for (const auto& outbox : all_.outboxes_) from.push_back(outbox[static_cast<std::size_t>(rank_)]);
      all_.barrier_.arrive_and_wait();
      return from;
    }
    // The operators and solvers never send one rank's values to another alone.
    void send(int, std::span<const float>) const override { throw std::logic_error("send: not offered by thread ranks"); }
    void receive(int, std::span<float>) const override { throw std::logic_error("receive: not offered by thread ranks"); }
    [[noreturn]] void abort(int) const override { throw std::logic_error("a rank aborted"); }

   private:
    ThreadRanks& all_;
    int rank_;
  };

  template <typename T>
  void sum(std::vector<std::span<T>>& slots, int rank, std::span<T> values) {
    slots[static_cast<std::size_t>(rank)] = values;
    barrier_.arrive_and_wait();  // every rank's array is in its slot
    std::vector<T> total(values.size(), T(0));
    for (const auto& slot : slots)
      for (std::size_t i = 0; i < total.size(); ++i) total[i] += slot[i];
    barrier_.arrive_and_wait();  // every rank has read every slot
    std::copy(total.begin(), total.end(), values.begin());
  }

  std::barrier<> barrier_;
  std::vector<std::span<float>> floats_;
  std::vector<std::span<double>> doubles_;
  std::vector<std::string> texts_;
  std::vector<std::vector<std::vector<float>>> outboxes_;
  std::vector<Rank> ranks_;
};

// A sphere of 30 views around a 20^3 volume, the data a smooth blob's projections plus noise.
struct Problem {
  VolumeLayout layout = VolumeLayout::centred({20, 20, 20}, Eigen::Vector3d::Constant(1.0));
  std::vector<ProjectionMatrix> views;
  ProjectionStack b;
  Problem() {
    const Detector d{32, 28, 1.2, 1.2};
    const Intrinsics K = Intrinsics::from_setup(600, d, d.centre_px());
    std::mt19937 random(7);
    std::normal_distribution<double> normal;
    for (int v = 0; v < 30; ++v) {
      const Eigen::Vector3d direction = Eigen::Vector3d(normal(random), normal(random), normal(random)).normalized();
      views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(direction), Eigen::Vector3d(0, 0, 400))));
    }
    Volume blob(layout);
    for (int k = 0; k < 20; ++k)
      for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 20; ++i)
          blob.at(i, j, k) =
              static_cast<float>(std::exp(-((i - 9.5) * (i - 9.5) + (j - 8) * (j - 8) + (k - 11) * (k - 11)) / 20.0));
    JosephOperator(views, layout, d.rows, d.cols).apply(blob, b);
    for (float& p : b.data) p += static_cast<float>(0.01 * normal(random));
  }
  // Rank r's views and data.
  std::vector<int> share(int r, int n) const { return dealt_share(static_cast<int>(views.size()), r, n); }
  ProjectionStack data_of(const std::vector<int>& mine) const {
    ProjectionStack out(static_cast<int>(mine.size()), b.rows, b.cols);
    for (std::size_t k = 0; k < mine.size(); ++k)
      std::copy_n(b.view(mine[k]), b.pixels_per_view(), out.view(static_cast<int>(k)));
    return out;
  }
  std::shared_ptr<const ProjectionOperator> local(const std::vector<int>& mine) const {
    return JosephOperator(views, layout, b.rows, b.cols).subset(mine);
  }
};

// What the spread runs must reproduce: WLS-CG (8 iterations, penalty `lambda`), SIRT (10) and
// OS-SQS (3 epochs of 4 subsets) on one process.
struct SingleProcess {
  WlsOptions cg_options;
  OsSqsOptions os_options;
  std::vector<std::vector<int>> subsets;
  Volume cg, sirt, os;
  SingleProcess(const Problem& p, double lambda) : cg(p.layout), sirt(p.layout), os(p.layout) {
    const JosephOperator whole(p.views, p.layout, p.b.rows, p.b.cols);
    cg_options.iterations = 8;
    cg_options.lambda = lambda;
    solve_wls_cg(whole, p.b, nullptr, cg, cg_options);
    solve_sirt(whole, p.b, sirt, {10, 1.0, true});
    subsets = ordered_subsets(p.views, 4, Eigen::Vector3d::Zero());
    os_options.epochs = 3;
    solve_os_sqs(whole, p.b, nullptr, os, subsets, os_options);
  }
};

double largest_difference(const Volume& a, const Volume& b) {
  double top = 0, worst = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    top = std::max(top, double(std::abs(a.data[i])));
    worst = std::max(worst, double(std::abs(a.data[i] - b.data[i])));
  }
  return worst / top;
}

// Every rank runs `solve(its operator, its data, its volume, its views, its rank)`; returns each
// rank's volume.
template <typename Solve>
std::vector<Volume> on_ranks(const Problem& p, int n, Solve solve) {
  ThreadRanks ranks(n);
  std::vector<Volume> out(static_cast<std::size_t>(n), Volume(p.layout));
  std::vector<std::thread> threads;
  for (int r = 0; r < n; ++r)
    threads.emplace_back([&, r] {
      const std::vector<int> mine = p.share(r, n);
      const ViewSplitOperator A(p.local(mine), ranks.rank(r));
      solve(A, p.data_of(mine), out[static_cast<std::size_t>(r)], mine, r);
    });
  for (auto& t : threads) t.join();
  return out;
}

TEST(ViewSplit, DealsEveryViewToOneRankInTurn) {
  EXPECT_EQ(dealt_share(7, 0, 3), (std::vector<int>{0, 3, 6}));
  EXPECT_EQ(dealt_share(7, 2, 3), (std::vector<int>{2, 5}));
  EXPECT_TRUE(dealt_share(2, 2, 3).empty());  // more ranks than views: a rank may hold none
  EXPECT_THROW(dealt_share(7, 3, 3), std::invalid_argument);
}

// <A x, y> summed over the ranks' views equals <x, A' y> with A' y summed over the ranks.
TEST(ViewSplit, IsAdjointAcrossTheRanks) {
  const Problem p;
  std::mt19937 random(3);
  std::uniform_real_distribution<float> uniform(-1, 1);
  Volume x(p.layout);
  for (float& v : x.data) v = uniform(random);
  std::vector<double> forward(3), backward(3);
  on_ranks(p, 3, [&](const ProjectionOperator& A, const ProjectionStack& y, Volume& back, const std::vector<int>&, int r) {
    ProjectionStack Ax;
    A.apply(x, Ax);
    double ax_y = 0;
    for (std::size_t i = 0; i < Ax.data.size(); ++i) ax_y += double(Ax.data[i]) * y.data[i];
    A.apply_adjoint(y, back);
    double x_aty = 0;
    for (std::size_t i = 0; i < x.data.size(); ++i) x_aty += double(x.data[i]) * back.data[i];
    forward[static_cast<std::size_t>(r)] = A.sum_over_range(ax_y);
    backward[static_cast<std::size_t>(r)] = x_aty;
  });
  for (int r = 0; r < 3; ++r) {
    EXPECT_NEAR(forward[static_cast<std::size_t>(r)], backward[static_cast<std::size_t>(r)],
                1e-5 * std::abs(backward[static_cast<std::size_t>(r)]));
    EXPECT_DOUBLE_EQ(forward[static_cast<std::size_t>(r)], forward[0]);  // every rank sees the same sum
  }
}

TEST(ViewSplit, SolversGiveTheSingleProcessVolumeOnEveryRank) {
  const Problem p;
  const SingleProcess one(p, 0.0);
  const WlsOptions& w = one.cg_options;
  const OsSqsOptions& os = one.os_options;
  const Volume &single_cg = one.cg, &single_sirt = one.sirt, &single_os = one.os;
  const std::vector<std::vector<int>>& subsets = one.subsets;
  for (int n : {2, 3}) {
    for (const Volume& x :
         on_ranks(p, n, [&](const ProjectionOperator&A, const ProjectionStack&b, Volume&x, const std::vector<int>&, int) {
           solve_wls_cg(A, b, nullptr, x, w);
         }))
      EXPECT_LT(largest_difference(single_cg, x), 1e-5) << "WLS-CG over " << n << " ranks";
    for (const Volume& x :
         on_ranks(p, n, [&](const ProjectionOperator&A, const ProjectionStack&b, Volume&x, const std::vector<int>&, int) {
           solve_sirt(A, b, x, {10, 1.0, true});
         }))
      EXPECT_LT(largest_difference(single_sirt, x), 1e-5) << "SIRT over " << n << " ranks";
    // OS-SQS: each rank takes its views of every subset (some of a rank's parts are empty).
    for (const Volume& x :
         on_ranks(p, n, [&](const ProjectionOperator&A, const ProjectionStack&b, Volume&x, const std::vector<int>&mine, int) {
           std::vector<std::vector<int>> local(subsets.size());
           for (std::size_t s = 0; s < subsets.size(); ++s)
             for (int v : subsets[s])
               if (const auto at = std::find(mine.begin(), mine.end(), v); at != mine.end())
                 local[s].push_back(static_cast<int>(at - mine.begin()));
           solve_os_sqs(A, b, nullptr, x, local, os);
         }))
      EXPECT_LT(largest_difference(single_os, x), 1e-5) << "OS-SQS over " << n << " ranks";
  }
}

// Slabs: every rank holds all views, its slab and its owned rows of each view.
struct SlabRank {
  std::shared_ptr<const SlabRows> rows;
  int rank = 0;
  // The rows rank `rank` owns of every view of `stack`, at the top of its range's height.
  ProjectionStack owned_rows(const ProjectionStack& stack, int height) const {
    ProjectionStack out(stack.views, height, stack.cols);
    for (int v = 0; v < stack.views; ++v) {
      const RowRange own = rows->owned(v, rank);
      std::copy_n(stack.view(v) + static_cast<std::size_t>(own.first) * static_cast<std::size_t>(stack.cols),
                  static_cast<std::size_t>(own.count) * static_cast<std::size_t>(stack.cols), out.view(v));
    }
    return out;
  }
};

// Every rank runs `solve(its operator, its data, its slab, its rank)`; returns the slabs put
// together into the whole volume.
template <typename Solve>
Volume on_slab_ranks(const Problem& p, int n, Solve solve) {
  ThreadRanks ranks(n);
  const auto rows = std::make_shared<const SlabRows>(p.views, p.layout, p.b.rows, n);
  std::vector<Volume> slabs(static_cast<std::size_t>(n));
  std::vector<std::thread> threads;
  for (int r = 0; r < n; ++r)
    threads.emplace_back([&, r] {
      const SlabSplitOperator A(p.views, p.layout, p.b.rows, p.b.cols, rows, ranks.rank(r));
      Volume& x = slabs[static_cast<std::size_t>(r)];
      x = Volume(A.domain());
      solve(A, SlabRank{rows, r}.owned_rows(p.b, A.range().rows), x, r);
    });
  for (auto& t : threads) t.join();
  Volume whole(p.layout);
  for (int r = 0; r < n; ++r) {
    const RowRange planes = slab_planes(p.layout.size[2], r, n);
    std::copy(slabs[static_cast<std::size_t>(r)].data.begin(), slabs[static_cast<std::size_t>(r)].data.end(),
              whole.data.begin() + static_cast<std::ptrdiff_t>(planes.first) * p.layout.size[0] * p.layout.size[1]);
  }
  return whole;
}

TEST(SlabSplit, EachViewsRowsAreOwnedOnceAndEverySlabStaysInItsFootprint) {
  const Problem p;
  const JosephOperator whole(p.views, p.layout, p.b.rows, p.b.cols);
  for (int n : {2, 3}) {
    const SlabRows rows(p.views, p.layout, p.b.rows, n);
    for (int v = 0; v < rows.views(); ++v) {
      std::vector<int> owners(static_cast<std::size_t>(p.b.rows), 0);
      for (int q = 0; q < n; ++q)
        for (int i = rows.owned(v, q).first; i < rows.owned(v, q).end(); ++i) ++owners[static_cast<std::size_t>(i)];
      EXPECT_EQ(std::count(owners.begin(), owners.end(), 1), p.b.rows) << "view " << v << " over " << n << " ranks";
    }
    // A slab of ones, projected on the whole detector: nothing outside its footprint.
    for (int q = 0; q < n; ++q) {
      Volume ones(p.layout);
      const RowRange planes = slab_planes(p.layout.size[2], q, n);
      std::fill(ones.data.begin() + static_cast<std::ptrdiff_t>(planes.first) * 400,
                ones.data.begin() + static_cast<std::ptrdiff_t>(planes.end()) * 400, 1.0f);
      ProjectionStack y;
      whole.apply(ones, y);
      for (int v = 0; v < y.views; ++v)
        for (int i = 0; i < y.rows; ++i) {
          const RowRange reach = rows.footprint(v, q);
          if (i >= reach.first && i < reach.end()) continue;
          for (int c = 0; c < y.cols; ++c)
            ASSERT_EQ(y.view(v)[static_cast<std::size_t>(i * y.cols + c)], 0.0f) << "view " << v << " row " << i << " slab " << q;
        }
    }
  }
}

TEST(SlabSplit, IsTheWholeOperatorAndAdjointAcrossTheRanks) {
  const Problem p;
  std::mt19937 random(5);
  std::uniform_real_distribution<float> uniform(-1, 1);
  Volume x(p.layout);
  for (float& v : x.data) v = uniform(random);
  ProjectionStack y = p.b;
  for (float& v : y.data) v = uniform(random);
  const JosephOperator whole(p.views, p.layout, p.b.rows, p.b.cols);
  ProjectionStack Ax_whole;
  whole.apply(x, Ax_whole);
  for (int n : {2, 3}) {
    std::vector<double> forward(static_cast<std::size_t>(n)), backward(static_cast<std::size_t>(n));
    std::vector<float> worst(static_cast<std::size_t>(n), 0.0f);
    on_slab_ranks(p, n, [&](const ProjectionOperator& A, const ProjectionStack&, Volume& slab, int r) {
      const SlabRank me{std::make_shared<const SlabRows>(p.views, p.layout, p.b.rows, n), r};
      const RowRange planes = slab_planes(p.layout.size[2], r, n);
      Volume x_slab(A.domain());
      std::copy_n(x.data.begin() + static_cast<std::ptrdiff_t>(planes.first) * 400, x_slab.data.size(), x_slab.data.begin());
      ProjectionStack Ax;
      A.apply(x_slab, Ax);
      const ProjectionStack expected = me.owned_rows(Ax_whole, A.range().rows), y_mine = me.owned_rows(y, A.range().rows);
      double ax_y = 0, x_aty = 0;
      for (std::size_t i = 0; i < Ax.data.size(); ++i) {
        worst[static_cast<std::size_t>(r)] =
            std::max(worst[static_cast<std::size_t>(r)], std::abs(Ax.data[i] - expected.data[i]));
        ax_y += double(Ax.data[i]) * y_mine.data[i];
      }
      A.apply_adjoint(y_mine, slab);
      for (std::size_t i = 0; i < slab.data.size(); ++i) x_aty += double(x_slab.data[i]) * slab.data[i];
      forward[static_cast<std::size_t>(r)] = A.sum_over_range(ax_y);
      backward[static_cast<std::size_t>(r)] = A.sum_over_domain(x_aty);
    });
    for (int r = 0; r < n; ++r) {
      EXPECT_LT(worst[static_cast<std::size_t>(r)], 1e-4) << "rank " << r << " of " << n << ": A x on its rows";
      EXPECT_NEAR(forward[static_cast<std::size_t>(r)], backward[static_cast<std::size_t>(r)],
                  1e-5 * std::abs(backward[static_cast<std::size_t>(r)]));
    }
  }
}

TEST(SlabSplit, SolversGiveTheSingleProcessVolume) {
  const Problem p;
  const SingleProcess one(p, 0.5);  // the Tikhonov penalty's sums over the volume are the ranks' sums
  const WlsOptions& w = one.cg_options;
  const OsSqsOptions& os = one.os_options;
  const Volume &single_cg = one.cg, &single_sirt = one.sirt, &single_os = one.os;
  const std::vector<std::vector<int>>& subsets = one.subsets;
  for (int n : {2, 3}) {
    EXPECT_LT(largest_difference(single_cg, on_slab_ranks(p, n,
                                                          [&](const ProjectionOperator& A, const ProjectionStack& b, Volume& x,
                                                              int) { solve_wls_cg(A, b, nullptr, x, w); })),
              1e-5)
        << "WLS-CG over " << n << " slabs";
    EXPECT_LT(
        largest_difference(single_sirt, on_slab_ranks(p, n,
                                                      [&](const ProjectionOperator& A, const ProjectionStack& b, Volume& x, int) {
                                                        solve_sirt(A, b, x, {10, 1.0, true});
                                                      })),
        1e-5)
        << "SIRT over " << n << " slabs";
    EXPECT_LT(largest_difference(single_os, on_slab_ranks(p, n,
                                                          [&](const ProjectionOperator& A, const ProjectionStack& b, Volume& x,
                                                              int) { solve_os_sqs(A, b, nullptr, x, subsets, os); })),
              1e-5)
        << "OS-SQS over " << n << " slabs";
  }
}

}  // namespace
}  // namespace ctk
