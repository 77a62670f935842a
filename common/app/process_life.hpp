#pragma once

#include <spdlog/logger.h>

#include <exception>
#include <memory>
#include <string>

namespace qswarm {

// What swarm-agent and swarm-supervisor do about the end of their own life: an escaping
// exception, and where they log.

// An exception that escapes a thread (one of Fast DDS's too: std::system_error when threads or
// memory run out) ends the process with exit code 1 and one line on stderr that names it, instead
// of an abort that the launcher can only report as a signal. Call first thing in main.
void exit_cleanly_on_uncaught_exceptions(const char* prog);

// An exception's what(), with a hint when it means the process ran out of threads or memory
// (std::system_error EAGAIN or ENOMEM, std::bad_alloc): what a main's last catch reports.
std::string describe_exception(const std::exception& e);

// The process's default logger: everything from info up to `log_path` (appended: a restarted
// agent adds to its log) and warnings to stderr; with no `log_path`, everything to stderr.
std::shared_ptr<spdlog::logger> make_process_logger(const std::string& name,
                                                    const std::string& log_path);

}  // namespace qswarm
