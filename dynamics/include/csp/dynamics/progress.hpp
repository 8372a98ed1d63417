// How far a long computation is. The libraries report through it and never print; apps/ draws it
// on a terminal (apps/progress.hpp), a test or a campaign may count it.
#pragma once

#include <functional>
#include <string_view>

namespace csp {

// `done` of `total` units of work in `stage` (e.g. "fitting effects", 3 of 13). A stage starts
// again at done = 0; callers report as often as is cheap, the receiver decides what to show.
using Progress = std::function<void(std::string_view stage, double done, double total)>;

// Report through `progress` when there is one.
inline void report(const Progress& progress, std::string_view stage, double done, double total) {
  if (progress) progress(stage, done, total);
}

}  // namespace csp
