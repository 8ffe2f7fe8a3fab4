#pragma once
// One small exception hierarchy for the whole library, and the single table that maps
// each kind of error to its command-line exit code and its name.

#include <stdexcept>
#include <string>

namespace qs {

/// The closed vocabulary of failures. Exit codes are part of the command-line contract.
enum class ErrorCode {
  Usage = 1,         ///< bad command-line arguments
  InvalidInput = 2,  ///< a mesh, landmark file or option value that qs cannot use
  Io = 3,            ///< a file that cannot be opened, read or written
  Solver = 4,        ///< a numerical step that failed (factorization, non-bijective map)
  Internal = 70,     ///< a bug in qs (EX_SOFTWARE)
};

/// The process exit code for an error code (the enum's value, spelled out for readers).
int exit_code(ErrorCode code);
/// A short lower-case name: "usage", "invalid input", "i/o", "solver", "internal".
const char* error_name(ErrorCode code);

/// Base of every exception qs throws on purpose.
class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

class UsageError : public Error {
 public:
  explicit UsageError(const std::string& m) : Error(ErrorCode::Usage, m) {}
};
class InvalidInput : public Error {
 public:
  explicit InvalidInput(const std::string& m) : Error(ErrorCode::InvalidInput, m) {}
};
class IoError : public Error {
 public:
  explicit IoError(const std::string& m) : Error(ErrorCode::Io, m) {}
};
class SolverError : public Error {
 public:
  explicit SolverError(const std::string& m) : Error(ErrorCode::Solver, m) {}
};
class InternalError : public Error {
 public:
  explicit InternalError(const std::string& m) : Error(ErrorCode::Internal, m) {}
};

}  // namespace qs
