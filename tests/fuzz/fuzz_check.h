// What the fuzz targets share: a failed property aborts with a message (libFuzzer then saves
// the input as a crash reproducer), and the CLI JSON adapters are checked the same way.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

namespace facet::fuzz {

[[noreturn]] inline void Fail(const char* target, const std::string& what) {
  std::fprintf(stderr, "%s: property failed: %s\n", target, what.c_str());
  std::abort();
}

// A CLI JSON adapter (text in, {json, error} out): a refusal has a message; an answer is a
// JSON object; and the answer does not depend on how the input was written: the input
// re-serialised by nlohmann (other whitespace, shortest round-trip numbers) gives the same
// document, "time_ms" aside. That also catches answers that depend on uninitialised memory.
template <typename Adapter>
void CheckJsonAdapter(const char* target, const std::string& text, Adapter adapter) {
  const auto result = adapter(text);
  if (!result.ok()) {
    if (result.error.empty()) Fail(target, "refused without a message");
    return;
  }
  nlohmann::json answer = nlohmann::json::parse(result.json, nullptr, /*allow_exceptions=*/false);
  if (answer.is_discarded() || !answer.is_object()) Fail(target, "the answer is not a JSON object:\n" + result.json);
  // The input parsed (the adapter accepted it), so this cannot throw.
  const std::string rewritten = nlohmann::json::parse(text).dump();
  const auto again = adapter(rewritten);
  if (!again.ok()) Fail(target, "the re-serialised input is refused: " + again.error + "\n" + rewritten);
  nlohmann::json answer_again = nlohmann::json::parse(again.json, nullptr, false);
  answer.erase("time_ms");
  answer_again.erase("time_ms");
  if (answer != answer_again) {
    Fail(target, "the re-serialised input gives another answer:\n" + answer.dump(1) + "\n---\n" + answer_again.dump(1));
  }
}

}  // namespace facet::fuzz
