// `swarm export --mcap RUN_DIR`: a run's run.mcap rebuilt from its records.pb.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "common/mcap/file_check.hpp"
#include "common/record/mcap_export.hpp"
#include "common/record/run_dir.hpp"
#include "launcher/commands.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

// `swarm export --mcap RUN_DIR [--out FILE]`: run.mcap rebuilt from records.pb, for runs recorded
// before run.mcap existed and for a run.mcap cut short (a supervisor killed mid-run). 0 written; 2
// bad input (not a run directory, --out in no directory, a records.pb cut mid-record: its whole
// records are exported and the message says where it was cut); 3 the file could not be written.
int export_run(const std::string& run_dir, const std::string& out_flag) {
  const RunDir dir(run_dir);
  const fs::path out = out_flag.empty() ? dir.mcap() : fs::path(out_flag);
  std::error_code ec;
  const fs::path parent = fs::absolute(out, ec).parent_path();
  if (!out_flag.empty() && (ec || !fs::is_directory(parent, ec) || ec)) {
    std::cerr << "swarm export: --out " << out_flag << ": " << parent.string()
              << " is not a directory" << (ec ? " (" + ec.message() + ")" : std::string()) << "\n";
    return 2;
  }
  const fs::file_status st = fs::symlink_status(out, ec);
  if (fs::exists(st) && !fs::is_regular_file(fs::status(out, ec))) {
    std::cerr << "swarm export: " << (out_flag.empty() ? "RUN_DIR/" : "--out ") << out.string()
              << ": not a regular file, not replaced\n";
    return 2;
  }
  const bool replacing = out == dir.mcap() && fs::exists(out, ec);
  const mcap::FileCheck before = replacing ? mcap::check_file(out) : mcap::FileCheck{};
  ExportResult r;
  try {
    r = export_mcap(dir, out);
  } catch (const ExportError& e) {
    std::cerr << "swarm export: " << e.what() << "\n";
    return 2;
  }
  if (!r.write_error.empty()) {
    std::cerr << "swarm export: could not write " << r.write_error << "\n";
    return 3;
  }
  if (!r.kept.empty()) {
    std::cerr << "swarm export: " << r.partial << "; " << r.kept << "\n";
    return 2;
  }
  if (replacing && !before.complete)
    std::cout << "swarm export: " << out.string() << " was incomplete (" << before.problem
              << "); rebuilt from " << dir.records().filename().string() << "\n";
  const auto n = [&](Stream s) { return r.messages[static_cast<std::size_t>(s)]; };
  std::cout << "swarm export: " << r.records << " records -> " << out.string() << " ("
            << n(Stream::kAgentSamples) << " samples, " << n(Stream::kGraph) << " graph snapshots, "
            << n(Stream::kEvents) << " events, " << n(Stream::kScene) << " scenes)\n";
  if (!r.partial.empty()) {
    std::cerr << "swarm export: " << r.partial << ": exported those, not the rest\n";
    return 2;
  }
  return 0;
}

}  // namespace

Command add_export_command(CLI::App& app) {
  struct Options {
    std::string run_dir, out;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export", "rebuild a run's run.mcap (Foxglove, Lichtblick) from its records.pb");
  cmd->add_option("--mcap", o->run_dir, "the run directory whose records.pb to export")->required();
  cmd->add_option("--out", o->out, "the MCAP file to write (default RUN_DIR/run.mcap)");
  return [cmd, o]() -> std::optional<int> {
    if (!*cmd) return std::nullopt;
    return export_run(o->run_dir, o->out);
  };
}

}  // namespace qswarm
