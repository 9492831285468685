// What keeps two Facets from writing one project (issue 25): the project's lock
// (core/util/project_lock.h), taken when a project is opened or first saved under a name and
// released on New, on opening another project and at exit; and the project file's identity
// when this session last read or wrote it (core/util/file_identity.h), checked before Save
// overwrites it.
//
// A project another Facet holds opens read-only (the user's choice in the GUI's dialog, or
// by itself at the start of an offscreen run with --autosave): nothing writes the project or
// its recovery file, and Save becomes Save as. An offscreen run without --autosave writes
// nothing until a script saves, so it takes a lock only then (renders of a project open
// elsewhere, and test suites rendering one shared sample at once, do not get in each
// other's way). A save whose file changed on disk since is refused; the GUI asks
// (overwrite, save as, cancel), a script's `command save` fails with the reason.
#pragma once

#include <string>

#include "core/util/file_identity.h"
#include "core/util/project_lock.h"

namespace facet::app {

// A question the shell asks the user on the next frame (DrawFrame opens its dialog).
enum class GuardQuestion {
  kNone,
  kOpenLocked,   // question_path is open in another Facet: open read-only, a copy, or cancel
  kSaveChanged,  // question_path changed on disk since it was read here: overwrite, save as, cancel
};

struct ProjectGuard {
  // Whether opening a project takes its lock (the GUI, `render --autosave`), or only saving
  // does (`render` without it). A setting of the session: ResetProjectGuard keeps it.
  bool lock_on_open = true;
  ProjectLock lock;              // held while AppState::project_path is open here for writing
  bool read_only = false;        // another Facet holds project_path: this session never writes it
  std::string read_only_reason;  // DescribeLockHolder's text, for the title and the log
  FileIdentity known;            // project_path as last read or written here
  GuardQuestion question = GuardQuestion::kNone;
  std::string question_path;
  std::string question_text;  // the holder, or what changed
};

// Releases the lock and forgets the project file (New, another project); keeps lock_on_open.
inline void ResetProjectGuard(ProjectGuard* guard) {
  const bool lock_on_open = guard->lock_on_open;
  *guard = ProjectGuard{};
  guard->lock_on_open = lock_on_open;
}

// How OpenProject treats the project's lock.
enum class OpenAccess {
  kEdit,            // take the lock (if lock_on_open); when another Facet holds it, refuse and ask (kOpenLocked)
  kReadOnly,        // do not take it: nothing is written to the project or its recovery file
  kEditOrReadOnly,  // take it when free, else open read-only (an offscreen run's start)
};

}  // namespace facet::app
