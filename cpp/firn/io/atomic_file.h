#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace firn {

// Writes a file so that a reader never sees half of it: `write` fills a temporary file beside `path` through a
// stream that throws on any failed write, then the temporary file is renamed over `path`. On failure the
// temporary file is removed, `path` is left as it was, and WriteError says why (the failed call's errno: ENOSPC,
// EROFS...); a firn::Cancelled thrown by `write` passes through as itself, with the same clean-up. Creates missing
// parent folders.
void writeFileAtomically(const std::string &path, const std::function<void(std::ostream &)> &write);

}  // namespace firn
