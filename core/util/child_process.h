// Running an external program (COLMAP) as a child process: no shell (the arguments go to it
// as they are), its own process group (so that a cancel ends it and everything it started),
// its output appended to a log file, and a cancel test polled while it runs.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace facet {

// The executable `name` would run: `name` itself when it holds a '/', else the first
// executable regular file of that name along PATH. "" when there is none.
std::string FindExecutable(const std::string& name);

struct ChildProcessOptions {
  std::string executable;                                        // a path, or a name looked up along PATH
  std::vector<std::string> arguments;                            // argv[1...]
  std::string working_dir;                                       // the child's current folder; "" keeps the parent's
  std::string log_path;                                          // stdout and stderr are appended here ("" : /dev/null)
  std::vector<std::pair<std::string, std::string>> environment;  // set or replaced in the child's
  // Polled every poll_ms while the child runs; true ends the child's process group (SIGTERM,
  // then SIGKILL after kill_grace_ms) and the result says cancelled.
  std::function<bool()> should_cancel;
  int poll_ms = 50;
  int kill_grace_ms = 2000;
};

struct ChildProcessResult {
  bool started = false;    // false: could not be started; see error
  bool cancelled = false;  // ended by should_cancel
  int exit_code = -1;      // when it exited by itself
  int signal = 0;          // when a signal ended it
  double time_ms = 0.0;
  std::string error;  // why it could not be started, "" otherwise
  bool Succeeded() const { return started && !cancelled && signal == 0 && exit_code == 0; }
};

// Runs the child to its end (or its cancel) and returns how it ended.
ChildProcessResult RunChildProcess(const ChildProcessOptions& options);

}  // namespace facet
