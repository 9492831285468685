// The recovery file (core/io/recovery_io.h), which the app reads at start after a crash: any
// bytes either load or are refused with a message. A file that loads must write back, the
// written text must load back to the same document (project, undo and redo history, clean
// state) and write the same text again; the loaded history must be live: undoing all of it
// and redoing all of it returns to the loaded project.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/recovery_io.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

bool SameDocument(const facet::Document& a, const facet::Document& b) {
  return a.project() == b.project() && a.undo_stack() == b.undo_stack() && a.redo_stack() == b.redo_stack() &&
         a.clean_undo_depth() == b.clean_undo_depth() && a.clean_is_unreachable() == b.clean_is_unreachable();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using facet::fuzz::Fail;
  constexpr const char* kTarget = "fuzz_recovery";
  const std::string text(reinterpret_cast<const char*>(data), size);
  const facet::RecoveryLoadResult loaded = facet::RecoveryFromJson(text);
  if (!loaded.ok()) return 0;
  std::string error;
  const std::string written = facet::RecoveryToJson(loaded.document, &error);
  if (!error.empty()) Fail(kTarget, "a loaded recovery file cannot be written: " + error);
  const facet::RecoveryLoadResult reloaded = facet::RecoveryFromJson(written);
  if (!reloaded.ok()) Fail(kTarget, "the written text does not load: " + reloaded.error + "\n" + written);
  if (!SameDocument(reloaded.document, loaded.document)) Fail(kTarget, "the written text loads back different");
  if (facet::RecoveryToJson(reloaded.document, &error) != written) Fail(kTarget, "writing it again changes the text");

  facet::Document live = loaded.document;
  while (live.CanUndo()) {
    if (!live.Undo()) Fail(kTarget, "an undo of the loaded history failed");
  }
  while (live.CanRedo()) {
    if (!live.Redo()) Fail(kTarget, "a redo of the loaded history failed");
  }
  // Redoing everything ends at the last redo; that equals the loaded project only when the
  // file had no redo stack.
  if (loaded.document.redo_stack().empty() && !(live.project() == loaded.document.project())) {
    Fail(kTarget, "undo all + redo all does not return to the loaded project");
  }
  return 0;
}
