#include "common/app/process_life.hpp"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <new>
#include <system_error>
#include <vector>

#include "common/dds/participant.hpp"

namespace qswarm {

std::string describe_exception(const std::exception& e) {
  std::string what = e.what();
  const auto* sys = dynamic_cast<const std::system_error*>(&e);
  const bool out_of_resources =
      dynamic_cast<const std::bad_alloc*>(&e) != nullptr ||
      (sys != nullptr && (sys->code() == std::errc::resource_unavailable_try_again ||
                          sys->code() == std::errc::not_enough_memory));
  if (out_of_resources)
    what += " (out of threads or memory: run fewer agents, or raise the process and thread limits)";
  return what;
}

namespace {
const char* g_prog = "qswarm";

[[noreturn]] void on_terminate() {
  std::string what = "std::terminate without an exception";
  if (const std::exception_ptr e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& ex) {
      what = "uncaught exception: " + describe_exception(ex);
      if (creating_participant() && dynamic_cast<const std::system_error*>(&ex) != nullptr &&
          what.find("out of threads") == std::string::npos)
        what +=
            " (while Fast DDS started its participant's threads: out of threads or memory? run "
            "fewer agents, or raise the process and thread limits)";
    } catch (...) {
      what = "uncaught exception of an unknown type";
    }
  }
  std::fprintf(stderr, "%s: fatal: %s\n", g_prog, what.c_str());
  std::fflush(stderr);
  std::_Exit(1);
}
}  // namespace

void exit_cleanly_on_uncaught_exceptions(const char* prog) {
  g_prog = prog;
  std::set_terminate(on_terminate);
}

std::shared_ptr<spdlog::logger> make_process_logger(const std::string& name,
                                                    const std::string& log_path) {
  std::vector<spdlog::sink_ptr> sinks;
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  // With a log file, the terminal gets warnings only; without one (a container, whose log is its
  // output), everything.
  console->set_level(log_path.empty() ? spdlog::level::info : spdlog::level::warn);
  sinks.push_back(console);
  if (!log_path.empty())
    sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(log_path, false));
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_level(spdlog::level::info);
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  return logger;
}

}  // namespace qswarm
