// ctk phantom: list the built-in phantoms, write any of them as an editable ctk-phantom/1 file.
#include <iostream>

#include "commands.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"

namespace ctk::tools {

void register_phantom(CLI::App& app) {
  auto name = std::make_shared<std::string>();
  auto out = std::make_shared<std::filesystem::path>();
  CLI::App* cmd = app.add_subcommand("phantom", "List the built-in phantoms, or write one as a ctk-phantom/1 file");
  cmd->add_option("name", *name, "Built-in phantom to write (omit to list them)");
  cmd->add_option("--out", *out, "File to write (default: <name>.json)");
  cmd->callback([name, out] {
    if (name->empty()) {
      for (const auto& n : builtin_phantom_names())
        std::cout << n << ": " << builtin_phantom(n).primitives.size() << " primitives\n";
      return;
    }
    const Phantom p = builtin_phantom(*name);
    const std::filesystem::path file = out->empty() ? std::filesystem::path(*name + ".json") : *out;
    write_phantom(p, file);
    std::cout << p.name << " (" << p.primitives.size() << " primitives) written to " << file.string() << "\n";
  });
}

}  // namespace ctk::tools
