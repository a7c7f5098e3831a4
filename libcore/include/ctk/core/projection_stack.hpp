#pragma once
// A stack of projections, views x rows x cols, float32, row-major per view (u = column fastest).
#include <cstddef>

#include "ctk/core/float_buffer.hpp"

namespace ctk {

/// A stack's pixels held elsewhere (a numpy array, a memory map), in the order of ProjectionStack.
/// T is float or const float.
template <class T>
struct StackSpanOf {
  int views = 0, rows = 0, cols = 0;
  T* data = nullptr;
  std::size_t pixels_per_view() const { return static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols); }
  T* view(int v) const { return data + static_cast<std::size_t>(v) * pixels_per_view(); }
};
using StackSpan = StackSpanOf<float>;
using ConstStackSpan = StackSpanOf<const float>;

struct ProjectionStack {
  int views = 0, rows = 0, cols = 0;
  FloatBuffer data;

  ProjectionStack() = default;
  ProjectionStack(int v, int r, int c)
      : views(v),
        rows(r),
        cols(c),
        data(static_cast<std::size_t>(v) * static_cast<std::size_t>(r) * static_cast<std::size_t>(c), 0.0f) {}
  operator StackSpan() { return {views, rows, cols, data.data()}; }
  operator ConstStackSpan() const { return {views, rows, cols, data.data()}; }
  std::size_t pixels_per_view() const { return static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols); }
  float* view(int v) { return data.data() + static_cast<std::size_t>(v) * pixels_per_view(); }
  const float* view(int v) const { return data.data() + static_cast<std::size_t>(v) * pixels_per_view(); }
  float& at(int v, int row, int col) {
    return view(v)[static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(col)];
  }
  float at(int v, int row, int col) const {
    return view(v)[static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(col)];
  }
};

}  // namespace ctk
