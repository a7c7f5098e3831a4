#pragma once
// The HTML page each command writes beside its JSON report (html_report.hpp), and its path
// printed, so a user knows what to open.
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/core/html_report.hpp"

namespace ctk::tools {

inline void write_and_name_run_page(const std::string& command, const std::string& brief, const nlohmann::json& report,
                                    const std::vector<std::filesystem::path>& pictures, const std::filesystem::path& page,
                                    const std::string& next = "") {
  write_run_page(command, brief, report, pictures, page, next);
  std::cout << "report page: " << page.string() << "\n";
}

}  // namespace ctk::tools
