// csp can: the arm's joint drives on a CANopen bus (docs/can.md). `csp can eds` and `csp can dbc`
// print the files generated from the drives' object table.
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "csp/can/export.hpp"

namespace csp::cli {
namespace {

struct CanArguments {
  int node = 1;
  std::string out;
};

int write_text(const std::string& text, const std::string& path) {
  if (path.empty()) {
    std::cout << text;
    return 0;
  }
  std::ofstream file(path);
  if (!(file << text)) throw UsageError("--out " + path + ": cannot write the file");
  return 0;
}

}  // namespace

Command add_can_command(CLI::App& app) {
  auto args = std::make_shared<CanArguments>();
  CLI::App* cmd = app.add_subcommand("can", "The joint drives as CANopen CiA 402 nodes: EDS and DBC (docs/can.md)");
  cmd->require_subcommand(1);
  CLI::App* eds = cmd->add_subcommand("eds", "Print the EDS (CiA 306) of a joint drive");
  eds->add_option("--node", args->node, "Node id 1..7 = joint 1..7 (the default assignment)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
  eds->add_option("-o,--out", args->out, "Write to this file instead of stdout");
  CLI::App* dbc = cmd->add_subcommand("dbc", "Print the DBC of the bus (default mapping, nodes 1..7)");
  dbc->add_option("-o,--out", args->out, "Write to this file instead of stdout");
  return [args, eds] {
    if (eds->parsed()) return write_text(can::make_eds(can::panda_joint_drive(args->node)), args->out);
    return write_text(can::make_dbc(can::BusSettings{}), args->out);
  };
}

}  // namespace csp::cli
