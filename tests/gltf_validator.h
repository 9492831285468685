// The Khronos glTF Validator on a file a test wrote: tests/gltf/validate.js (the npm package
// pinned in tests/gltf/package-lock.json, installed by scripts/setup.sh) run with node. Every
// suite that writes a .glb checks it with CHECK_GLTF_VALID; a missing node or validator fails
// the check with the reason (never a skip).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

namespace facet::testing {

struct GltfValidation {
  bool ran = false;    // the validator produced a report for the file
  std::string error;   // why it did not (node or the package missing, unreadable file)
  std::string validator_version;
  int errors = 0, warnings = 0, infos = 0, hints = 0;
  std::string messages;  // every error and warning, one per line
};

inline GltfValidation ValidateGltf(const std::string& path) {
  GltfValidation v;
  const std::string script = std::string(FACET_SOURCE_DIR) + "/tests/gltf/validate.js";
  const std::string out = path + ".validator.json";
  const std::string err = path + ".validator.err";
  const std::string command = "node '" + script + "' '" + path + "' > '" + out + "' 2> '" + err + "'";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  std::stringstream err_text;
  err_text << std::ifstream(err).rdbuf();
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  if ((code != 0 && code != 1) || line.empty()) {
    v.error = "the glTF Validator did not run (exit " + std::to_string(code) + "): " + err_text.str() + line +
              " (node and tests/gltf/node_modules come from scripts/setup.sh)";
    return v;
  }
  const nlohmann::json report = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (report.is_discarded()) {
    v.error = "unreadable validator output: " + line;
    return v;
  }
  v.ran = true;
  v.validator_version = report.value("validator", "");
  v.errors = report.value("errors", 0);
  v.warnings = report.value("warnings", 0);
  v.infos = report.value("infos", 0);
  v.hints = report.value("hints", 0);
  for (const auto& m : report.value("messages", nlohmann::json::array())) v.messages += m.get<std::string>() + "\n";
  return v;
}

}  // namespace facet::testing

// Zero errors from the Khronos glTF Validator on `path`, with its messages on failure. The
// version and the counts go to the test's output (MESSAGE) for the record.
#define CHECK_GLTF_VALID(path)                                                                                      \
  do {                                                                                                              \
    const ::facet::testing::GltfValidation gltf_validation_ = ::facet::testing::ValidateGltf(path);                 \
    CHECK_MESSAGE(gltf_validation_.ran, "the glTF Validator did not run on " << (path) << ": "                      \
                                                                               << gltf_validation_.error);          \
    CHECK_MESSAGE(gltf_validation_.errors == 0,                                                                     \
                  "glTF Validator on " << (path) << ":\n" << gltf_validation_.messages);                           \
    if (gltf_validation_.ran)                                                                                       \
      MESSAGE("glTF Validator " << gltf_validation_.validator_version << " on " << (path) << ": "                   \
                                << gltf_validation_.errors << " errors, " << gltf_validation_.warnings            \
                                << " warnings, " << gltf_validation_.infos << " infos, " << gltf_validation_.hints \
                                << " hints");                                                                       \
  } while (false)
