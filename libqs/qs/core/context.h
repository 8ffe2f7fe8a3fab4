#pragma once
// What long library calls receive besides their inputs: a log sink, a progress callback,
// and a cancel flag. The library never writes to stdout or stderr itself.

#include <atomic>
#include <functional>
#include <string>

namespace qs {

enum class LogLevel { Debug, Info, Warning };

struct Context {
  /// Receives notes and warnings; null drops them.
  std::function<void(LogLevel, const std::string&)> log;
  /// Receives (stage, fraction done in [0,1]); null drops them.
  std::function<void(const std::string&, double)> progress;
  /// When set and true, long calls stop at the next check and throw an Internal qs::Error "cancelled".
  const std::atomic<bool>* cancel = nullptr;
  int threads = 0;  ///< 0: all hardware threads

  void info(const std::string& m) const { if (log) log(LogLevel::Info, m); }
  void warn(const std::string& m) const { if (log) log(LogLevel::Warning, m); }
  void report(const std::string& stage, double fraction) const {
    if (progress) progress(stage, fraction);
  }
  /// The same context without the progress callback: for inner calls whose own progress would
  /// drown the caller's.
  Context without_progress() const {
    Context c = *this;
    c.progress = nullptr;
    return c;
  }
  /// Throws when the cancel flag is raised.
  void check_cancel() const;
};

}  // namespace qs
