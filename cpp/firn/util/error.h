#pragma once

#include <stdexcept>
#include <string>

namespace firn {

// Bad input from the caller (NaN vertices, absurd settings). Python sees ValueError.
class InvalidArgument : public std::invalid_argument {
  public:
    using std::invalid_argument::invalid_argument;
};

// A request that would exceed a resource limit (voxel budget). Python sees firncore.BudgetError.
class BudgetExceeded : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// The caller asked a long computation to stop. Python sees firncore.Cancelled.
class Cancelled : public std::runtime_error {
  public:
    Cancelled() : std::runtime_error("cancelled") {}
};

// Reading or writing files failed. Python sees OSError.
class IoError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// A file could not be read: missing, unreadable, truncated or corrupted. Python sees firncore.ReadError (an
// OSError), so a caller that reads and writes in one call can tell "this input is bad" from "cannot write".
class ReadError : public IoError {
  public:
    using IoError::IoError;
};

// A file could not be written (full disk, read-only folder). Python sees firncore.WriteError (an OSError).
class WriteError : public IoError {
  public:
    using IoError::IoError;
};

}  // namespace firn
