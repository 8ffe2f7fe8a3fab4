#include "qs/core/error.h"

namespace qs {

int exit_code(ErrorCode code) { return static_cast<int>(code); }

const char* error_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::Usage: return "usage";
    case ErrorCode::InvalidInput: return "invalid input";
    case ErrorCode::Io: return "i/o";
    case ErrorCode::Solver: return "solver";
    case ErrorCode::Internal: return "internal";
  }
  return "internal";
}

}  // namespace qs
