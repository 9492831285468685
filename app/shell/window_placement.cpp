#include "app/shell/window_placement.h"

#include "core/util/file_read.h"
#include "core/util/file_write.h"

#include <fstream>

#include <nlohmann/json.hpp>

#include "app/shell/layout.h"

namespace facet::app {

std::optional<WindowRect> LoadWindowRect(const std::string& path) {
  std::string text, error;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &text, &error)) return std::nullopt;
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return std::nullopt;
  WindowRect r;
  for (const auto& [key, field] : {std::pair{"x", &r.x}, {"y", &r.y}, {"width", &r.width}, {"height", &r.height}}) {
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number_integer()) return std::nullopt;
    *field = it->get<int>();
  }
  return r;
}

bool SaveWindowRect(const std::string& path, const WindowRect& rect) {
  return WriteFileAtomically(
             path, nlohmann::json{{"x", rect.x}, {"y", rect.y}, {"width", rect.width}, {"height", rect.height}}.dump() +
                       "\n")
      .empty();
}

std::string WindowRectFilePath() {
  const std::string dir = ConfigDirectory();
  return dir.empty() ? std::string() : dir + "/window.json";
}

}  // namespace facet::app
