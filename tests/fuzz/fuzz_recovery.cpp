// The recovery file (core/io/recovery_io.h), which the app reads at start after a crash: any
// bytes either load or are refused with a message. The input is read twice: raw, as a whole
// file (version 2 records, or a version 1 JSON object: the framing, the checksums, the header);
// and as record contents, one JSON payload per line, which the harness frames into records with
// correct lengths and checksums (FrameRecoveryRecords), so that mutations reach the base and
// journal readers' content checks instead of stopping at a checksum. A file that loads must
// write back, the written text must load back to the same document (project, undo and redo
// history, clean state) and write the same text again; the loaded history must be live:
// undoing all of it and redoing all of it returns to the loaded project. A file that loads only
// in part (a journal record that does not apply, `dropped`) must load to exactly the document
// of the records before that one, framed alone, and that shorter file must load whole.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/io/recovery_io.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using facet::fuzz::Fail;
constexpr const char* kTarget = "fuzz_recovery";

bool SameDocument(const facet::Document& a, const facet::Document& b) {
  return a.project() == b.project() && a.undo_stack() == b.undo_stack() && a.redo_stack() == b.redo_stack() &&
         a.clean_undo_depth() == b.clean_undo_depth() && a.clean_is_unreachable() == b.clean_is_unreachable();
}

facet::RecoveryLoadResult Check(const std::string& text) {
  facet::RecoveryLoadResult loaded = facet::RecoveryFromText(text);
  if (!loaded.ok()) return loaded;
  std::string error;
  const std::string written = facet::RecoveryToText(loaded.document, &error);
  if (!error.empty()) Fail(kTarget, "a loaded recovery file cannot be written: " + error);
  const facet::RecoveryLoadResult reloaded = facet::RecoveryFromText(written);
  if (!reloaded.ok()) Fail(kTarget, "the written text does not load: " + reloaded.error + "\n" + written);
  if (!SameDocument(reloaded.document, loaded.document)) Fail(kTarget, "the written text loads back different");
  if (facet::RecoveryToText(reloaded.document, &error) != written) Fail(kTarget, "writing it again changes the text");

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
  return loaded;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Check(text);
  std::vector<std::string> payloads;
  for (size_t start = 0; start <= text.size();) {
    const size_t end = std::min(text.find('\n', start), text.size());
    payloads.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  const facet::RecoveryLoadResult loaded = Check(facet::FrameRecoveryRecords(payloads));
  if (loaded.ok() && !loaded.dropped.empty()) {
    // The journal stopped at journal[journal_records]: the base and the records before it.
    if (loaded.journal_records + 1 >= payloads.size()) Fail(kTarget, "dropped names no record: " + loaded.dropped);
    payloads.resize(loaded.journal_records + 1);
    const facet::RecoveryLoadResult prefix = facet::RecoveryFromText(facet::FrameRecoveryRecords(payloads));
    if (!prefix.ok()) Fail(kTarget, "the records before the one dropped do not load: " + prefix.error);
    if (!prefix.dropped.empty())
      Fail(kTarget, "the records before the one dropped load only in part: " + prefix.dropped);
    if (prefix.journal_records != loaded.journal_records) Fail(kTarget, "the prefix applies another number of records");
    if (!SameDocument(prefix.document, loaded.document))
      Fail(kTarget, "a partial load differs from the records before the one dropped");
  }
  return 0;
}
