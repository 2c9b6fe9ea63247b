// Final state: the last printed state of an external program's output, and how two of them
// differ. A correct program prints the same final state whether it is judged (print mode) or
// timed (perf mode), at every T and in every repetition, since the model is deterministic; a
// program that does less work when it is timed, or stores an answer, does not (docs/programs.md,
// "The check").
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace psweep {

// The last `n` lines of the file at `path` that hold anything but white space, each as its
// whitespace-separated fields joined by one space; fewer when the file has fewer. Reads only the
// file's end, so a print-mode output of 65 MB costs what its last state does.
std::vector<std::string> final_state(const std::string& path, std::size_t n);

// Where `mine` differs from `reference` (final_state's, both of one scene): the first line that
// differs, as "particle I: `LINE` here, `LINE` WHERE" (`where` names the reference, e.g. "in
// print mode"), or the line counts; nothing when they are the same.
std::optional<std::string> final_state_difference(const std::vector<std::string>& mine,
                                                  const std::vector<std::string>& reference,
                                                  const std::string& where);

}  // namespace psweep
