#pragma once
// The HTML page each run writes beside its JSON report (html_report.hpp): its brief, its report,
// and its pictures, captioned by what they show.
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "ctk/core/html_report.hpp"

namespace ctk::tools {

// "calibrated.residuals.png" -> "residuals": the part after the run's stem names the picture.
inline std::string caption_of(const std::filesystem::path& png, const std::string& stem) {
  std::string name = png.stem().string();
  if (name.rfind(stem, 0) == 0) name = name.substr(stem.size());
  while (!name.empty() && (name.front() == '.' || name.front() == '_' || name.front() == '-')) name.erase(0, 1);
  return name.empty() ? png.filename().string() : name;
}

// The page, with the command to run next under its verdict; its path is printed, so a user
// knows what to open.
inline void write_run_page(const std::string& command, const std::string& brief, const nlohmann::json& report,
                           const std::vector<std::filesystem::path>& pictures, const std::filesystem::path& page,
                           const std::string& next = "") {
  HtmlReport r{"ctk " + command, brief, report, {}, next};
  const std::string stem = page.stem().string().substr(0, page.stem().string().find('.'));
  for (const std::filesystem::path& p : pictures) r.pictures.emplace_back(caption_of(p, stem), p);
  write_html_report(r, page);
  std::cout << "report page: " << page.string() << "\n";
}

}  // namespace ctk::tools
