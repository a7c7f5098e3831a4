#include "ctk/core/provenance.hpp"

#include <gtest/gtest.h>

#include <array>

namespace ctk {

TEST(Provenance, RecordsTheInvocationQuotedAsAShellNeedsIt) {
  const std::array<const char*, 5> argv = {"ctk", "reconstruct", "--out", "my volume.nrrd", "it's"};
  set_invocation(static_cast<int>(argv.size()), argv.data());
  const nlohmann::json p = provenance();
  EXPECT_EQ(p.at("invocation"), "ctk reconstruct --out 'my volume.nrrd' 'it'\\''s'");
  const std::string version = p.at("ctk_version");
  EXPECT_EQ(version, build_version());
  EXPECT_NE(version.find(" ("), std::string::npos) << version;  // "<version> (<commit>)"
  set_invocation("library call");
  EXPECT_EQ(provenance().at("invocation"), "library call");
}

}  // namespace ctk
