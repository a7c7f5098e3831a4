// Pictures drawn with cairo: the canvas pastes pixels exactly and draws text where it is told
// (rotated text upright along its own box); the chart maps data onto its frame, labels round ticks
// (never "-0"), and puts its legend in the plot's top-right corner.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "ctk/core/chart.hpp"

namespace ctk {
namespace {

// Pixels of `picture` (BGR) inside `box` darker than mid-grey in every channel.
int dark_pixels(const cv::Mat& picture, const cv::Rect& box) {
  int n = 0;
  for (int r = box.y; r < box.y + box.height; ++r)
    for (int c = box.x; c < box.x + box.width; ++c) {
      const cv::Vec3b p = picture.at<cv::Vec3b>(r, c);
      n += p[0] < 128 && p[1] < 128 && p[2] < 128;
    }
  return n;
}

TEST(Canvas, PastesBlocksExactlyAndStartsWhite) {
  Canvas canvas(40, 30);
  cv::Mat grey(2, 3, CV_8UC1);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c) grey.at<unsigned char>(r, c) = static_cast<unsigned char>(10 * (3 * r + c));
  canvas.paste(grey, 5, 7, 4);
  const cv::Mat out = canvas.bgr();
  ASSERT_EQ(out.cols, 40);
  ASSERT_EQ(out.rows, 30);
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < 12; ++c) {
      const unsigned char g = static_cast<unsigned char>(10 * (3 * (r / 4) + c / 4));
      EXPECT_EQ(out.at<cv::Vec3b>(7 + r, 5 + c), cv::Vec3b(g, g, g)) << r << " " << c;
    }
  EXPECT_EQ(out.at<cv::Vec3b>(15, 5), cv::Vec3b(255, 255, 255));  // just below the pasted block
  // Colours keep their channels: BGR in, BGR out.
  cv::Mat blue(1, 1, CV_8UC3, cv::Scalar(200, 10, 20));
  canvas.paste(blue, 30, 20);
  EXPECT_EQ(canvas.bgr().at<cv::Vec3b>(20, 30), cv::Vec3b(200, 10, 20));
}

TEST(Canvas, DrawsTextWhereItIsToldAndTurnsIt) {
  Canvas canvas(200, 200);
  const double w = canvas.text_width("ctk 1/mm", 14);
  EXPECT_GT(w, 40);
  EXPECT_LT(w, 90);
  canvas.text("ctk 1/mm", {100, 50}, 14, colour::black, TextAnchor::centre);
  // Upwards from (30, 190): a tall narrow box above the point.
  canvas.text("ctk 1/mm", {30, 190}, 14, colour::black, TextAnchor::left, 90);
  const cv::Mat out = canvas.bgr();
  const int half = static_cast<int>(w / 2) + 2;
  EXPECT_GT(dark_pixels(out, {100 - half, 36, 2 * half, 18}), 40);  // centred on x = 100, above the baseline
  EXPECT_EQ(dark_pixels(out, {40, 60, 160, 70}), 0);                // below the level text, right of the turned one
  EXPECT_GT(dark_pixels(out, {16, 190 - static_cast<int>(w) - 2, 18, static_cast<int>(w) + 2}), 40);
  EXPECT_EQ(dark_pixels(out, {40, 130, 160, 70}), 0);  // nothing to the right of the turned text
}

TEST(Chart, MapsDataOntoItsFrameAndLabelsRoundTicks) {
  EXPECT_EQ(tick_label(-0.0), "0");
  EXPECT_EQ(tick_label(3 * 0.1), "0.3");
  EXPECT_EQ(tick_label(-2.5), "-2.5");
  EXPECT_EQ(nice_step(10, 5), 2);
  EXPECT_EQ(nice_step(0.7, 5), 0.2);
  Chart chart(400, 200, {-1, 1, 0, 10, "title", "x", "y"});
  const cv::Point2d a = chart.at(-1, 0), b = chart.at(1, 10), m = chart.at(0, 5);
  EXPECT_NEAR(b.x - a.x, 400, 1e-9);
  EXPECT_NEAR(a.y - b.y, 200, 1e-9);  // y grows upwards
  EXPECT_NEAR(m.x, (a.x + b.x) / 2, 1e-9);
  EXPECT_NEAR(m.y, (a.y + b.y) / 2, 1e-9);
}

TEST(Chart, PutsItsLegendInTheTopRightCorner) {
  Chart chart(400, 200, {0, 1, 0, 1, "", "", ""});
  chart.legend({{"before", colour::red, Mark::dot}, {"after", colour::green, Mark::line}});
  const cv::Mat out = chart.picture();
  const cv::Point2d corner = chart.at(1, 1);
  auto count = [&](const cv::Rect& box, const cv::Scalar& c) {
    int n = 0;
    for (int r = box.y; r < box.y + box.height; ++r)
      for (int k = box.x; k < box.x + box.width; ++k) {
        const cv::Vec3b p = out.at<cv::Vec3b>(r, k);
        n += std::abs(p[0] - c[0]) < 20 && std::abs(p[1] - c[1]) < 20 && std::abs(p[2] - c[2]) < 20;
      }
    return n;
  };
  const cv::Rect top_right(static_cast<int>(corner.x) - 120, static_cast<int>(corner.y), 120, 50);
  EXPECT_GT(count(top_right, colour::red), 10);
  EXPECT_GT(count(top_right, colour::green), 10);
  EXPECT_GT(dark_pixels(out, top_right), 20);  // the labels
  const cv::Rect elsewhere(static_cast<int>(chart.at(0, 0.6).x) + 2, static_cast<int>(chart.at(0, 0.6).y), 200, 100);
  EXPECT_EQ(count(elsewhere, colour::red) + count(elsewhere, colour::green), 0);
}

}  // namespace
}  // namespace ctk
