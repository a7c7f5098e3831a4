#pragma once
// Checks of numeric options with messages a user can read. CLI11 2.1's PositiveNumber and
// NonNegativeNumber are ranges up to the largest double, and their message prints that bound in
// full ("not in range 0.000000 to 1797693134862315708...", 310 digits).
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <string>

#include "ctk/core/error.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk::tools {

// The scan as a command works on it: binned by --bin on top of its own detector.binning.
inline ScanDescription read_scan_binned(const std::filesystem::path& file, int bin) {
  ScanDescription scan = read_scan(file);
  try {
    bin_scan(scan, bin);
  } catch (const std::invalid_argument&) {
    throw InputError("--bin", "",
                     std::to_string(bin) + " does not fit the " + std::to_string(scan.detector.cols) + " x " +
                         std::to_string(scan.detector.rows) + " detector of " + file.string());
  }
  if (bin > 1)
    std::cout << "detector binned " << scan.binning << " x " << scan.binning << ": " << scan.detector.cols << " x "
              << scan.detector.rows << " pixels of " << scan.detector.pitch_u_mm << " mm\n";
  return scan;
}

// A finite number above zero (`strictly`) or at least zero.
inline CLI::Validator finite_number_from_zero(bool strictly) {
  return CLI::Validator(
      [strictly](std::string& input) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(input, value) || !std::isfinite(value)) return "expected a finite number, got " + input;
        if (strictly ? value > 0 : value >= 0) return {};
        return std::string(strictly ? "expected a number above 0" : "expected a number of at least 0") + ", got " + input;
      },
      strictly ? "POSITIVE" : "NONNEGATIVE", strictly ? "positive number" : "non-negative number");
}

inline const CLI::Validator positive_number = finite_number_from_zero(true);

// A number in [0, 1): a factor a quantity must fall by.
inline const CLI::Validator fraction_below_one(
    [](std::string& input) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(input, value) || !(value >= 0 && value < 1))
        return "expected a number in [0, 1), got " + input;
      return {};
    },
    "[0, 1)", "fraction below one");
inline const CLI::Validator non_negative_number = finite_number_from_zero(false);

// A volume file whose extension names a format ctk writes, so a mistyped one is refused before
// any work.
inline const CLI::Validator volume_file_name(
    [](std::string& input) -> std::string {
      try {
        volume_format(input, "");
        return {};
      } catch (const InputError& e) {
        return e.what();
      }
    },
    "VOLUME", "volume file");

}  // namespace ctk::tools
