// The command-line verbs that work without a window: calibrate, solve, export. Each prints
// its result (JSON where a program may read it) on stdout, errors on stderr, and returns the
// process exit code (0 success, 1 unusable input).
#pragma once

#include <string>

namespace facet::app {

int RunCalibrateCommand(const std::string& lines_path);
int RunSolveCommand(const std::string& project_path, const std::string& output_path);
int RunExportCommand(const std::string& project_path, const std::string& output_path);

}  // namespace facet::app
