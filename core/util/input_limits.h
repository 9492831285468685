// Sizes past which an input is refused where it enters (the project reader, the CLI's JSON
// adapters, the GUI's operations), with the limit named in the message. Each is far above
// what a photo or a hand-built model needs, and chosen so that everything up to it finishes
// within a stated bound; the figures were measured with the Release build on the 2-core
// development machine (issue 25, "slow, not infinite").
#pragma once

#include <cstddef>

namespace facet {

// Sides of a prism or cylinder. A drum of 100,000 sides took tens of seconds a solve; a
// round tower needs a few dozen. At 1,024 sides a project with the street sample opens
// and solves in well under a second.
inline constexpr int kMaxPrimitiveSides = 1024;

// Primitives in one chain of AttachOnTop bases (a roof on a box on a box ...). Each level is
// re-applied after its base and followed by the solve's footprint rule; 64 is what those
// walks were always bounded to (deeper primitives silently stopped following), and a
// 2,000-box chain took 27-59 s a solve.
inline constexpr int kMaxAttachmentDepth = 64;

// Line segments given to one calibration (calibrate --lines, one photo of a project). The
// detector finds a few hundred to a few thousand on a 12-MP photo; 1e6 took tens of seconds.
inline constexpr std::size_t kMaxCalibrationSegments = 20000;

// Point matches given to `relate` (two-view geometry). Clicked matches are tens; a detector's
// a few thousand. 1e5 with 90 % outliers took 32 s.
inline constexpr std::size_t kMaxRelateMatches = 10000;

}  // namespace facet
