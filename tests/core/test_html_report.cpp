// The run's HTML page: self-contained (pictures as data URIs, even one still waiting in the run's
// output set), its report's numbers and per-view records in tables, text escaped.
#include "ctk/core/html_report.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "../test_support.hpp"
#include "ctk/core/chart.hpp"
#include "ctk/core/output_set.hpp"

namespace ctk {
namespace {

TEST(HtmlReport, EmbedsPicturesAndRendersTheReport) {
  const auto dir = testing::scratch_dir();
  HtmlReport r;
  r.title = "ctk calibrate";
  r.brief = "calibrated 3 of 4 views <fast> & well";
  r.next = "ctk diagnose --scan s.json --geometry g.json";
  r.report = {{"summary", {{"median_rms_px", 0.0123456789}, {"views", 4}}},
              {"views",
               {{{"index", 0}, {"status", "ok"}, {"rms_px", 0.01}},
                {{"index", 1}, {"status", "rejected"}, {"reason", "too few spheres"}}}},
              {"many", std::vector<int>(40, 7)},
              {"provenance", {{"ctk_version", "9.9"}}}};
  std::string page;
  {
    OutputSet outputs;  // the picture waits under a temporary name while the page is written
    write_png_atomically(cv::Mat(4, 6, CV_8UC3, cv::Scalar(0, 0, 255)), dir / "red.png");
    ASSERT_FALSE(std::filesystem::exists(dir / "red.png"));
    r.pictures = {{"residuals", dir / "red.png"}};
    page = html_report_text(r);
  }
  EXPECT_NE(page.find("calibrated 3 of 4 views &lt;fast&gt; &amp; well"), std::string::npos);
  // The verdict first: the brief and the next command before any number or picture.
  const auto verdict = page.find("<div class=\"verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  EXPECT_LT(verdict, page.find("calibrated 3 of 4"));
  EXPECT_LT(page.find("next: <code>ctk diagnose --scan s.json --geometry g.json</code>"), page.find("<img"));
  EXPECT_NE(page.find("<img src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // PNG's signature
  EXPECT_NE(page.find("<th>median_rms_px</th><td>0.0123</td>"), std::string::npos);         // three significant digits
  // One table for the per-view records, a column for every key any record has: what a record is
  // and its verdict first (index, status, reason), then the others in the report's key order.
  EXPECT_NE(page.find("<th>index</th><th>status</th><th>reason</th><th>rms_px</th>"), std::string::npos);
  EXPECT_NE(page.find("<td>1</td><td>rejected</td><td>too few spheres</td><td></td>"), std::string::npos);
  EXPECT_NE(page.find("&hellip; (40 values)"), std::string::npos);
  EXPECT_LT(page.find("results"), page.find("ctk_version"));  // provenance last
  r.pictures = {{"gone", dir / "missing.png"}};
  EXPECT_THROW(html_report_text(r), std::runtime_error);
}

}  // namespace
}  // namespace ctk
