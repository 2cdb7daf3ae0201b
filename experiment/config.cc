// `flowplan config show` and `flowplan config keys`.

#include <iostream>
#include <memory>

#include "experiment/commands.h"

namespace flowplan::experiment {

Command AddConfigCommand(CLI::App& app) {
  auto args = std::make_shared<ConfigArgs>();
  CLI::App* command = app.add_subcommand("config", "show the resolved config or list every key");
  command->require_subcommand(1);
  CLI::App* show = command->add_subcommand("show", "print the resolved config as YAML");
  args->Add(show, false);
  CLI::App* keys = command->add_subcommand("keys", "list every config key with its default and meaning");
  return {command, [args, show, keys] {
            if (show->parsed()) std::cout << ToYaml(args->Load());
            if (keys->parsed()) std::cout << config::FormatKeys(config::ListKeys(ExperimentConfig{}));
          }};
}

}  // namespace flowplan::experiment
