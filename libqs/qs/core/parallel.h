#pragma once
// The library's one parallel loop: 0..n-1 on a few threads, deterministic results.

#include <algorithm>
#include <atomic>
#include <exception>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "qs/core/context.h"

namespace qs {

/// The thread count of a parallel pass: `threads` when > 0, else context.threads when > 0, else one
/// per hardware thread (at least 1).
inline int thread_count(int threads, const Context& context) {
  if (threads > 0) return threads;
  if (context.threads > 0) return context.threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

namespace detail {
/// Set on the threads of a parallel_for that runs on more than one thread, while they run its body.
inline thread_local bool in_parallel_loop = false;
}  // namespace detail

/// Whether the calling thread runs the body of a parallel_for that uses more than one thread: an
/// inner pass that could split its work over threads of its own then runs on this one instead.
inline bool inside_parallel_loop() { return detail::in_parallel_loop; }

/// Calls body(i) for every i in [0, n) on min(thread_count(threads, context), n) threads, the calling
/// thread among them; indices are handed out in increasing order as threads come free. A body that
/// throws does not stop the others: every index runs, then the exception of the lowest index that
/// threw is rethrown, so which error surfaces does not depend on timing. A raised cancel flag stops
/// handing out indices; then \throws Error(Internal "cancelled") (context.check_cancel()).
/// With a non-empty `stage`, the calling thread reports (stage, indices done / n) after each index it
/// runs, and (stage, 1) when all have run without error. Results that depend only on i (written to
/// slot i, combined in index order afterwards) do not depend on the thread count.
template <class F>
void parallel_for(int n, int threads, const Context& context, F&& body, const std::string& stage = {}) {
  const int count = std::max(1, std::min(thread_count(threads, context), n));
  std::vector<std::exception_ptr> errors(static_cast<size_t>(std::max(n, 0)));
  std::atomic<int> next{0}, done{0};
  std::atomic<bool> stop{false};
  auto work = [&](bool reporting) {
    const bool outer = detail::in_parallel_loop;
    detail::in_parallel_loop = outer || count > 1;
    struct Restore {
      bool value;
      ~Restore() { detail::in_parallel_loop = value; }
    } restore{outer};
    for (int i; !stop.load() && !(context.cancel && context.cancel->load()) && (i = next++) < n;) {
      try {
        body(i);
      } catch (...) {
        errors[static_cast<size_t>(i)] = std::current_exception();
      }
      const int d = ++done;
      if (reporting && !stage.empty()) context.report(stage, static_cast<double>(d) / n);
    }
  };
  {
    // Joins the helpers however this block is left (a throwing progress callback, a thread that
    // cannot be started); `stop` keeps them from taking further indices then.
    struct Pool {
      std::vector<std::thread> threads;
      std::atomic<bool>& stop;
      ~Pool() {
        stop = true;
        for (auto& t : threads) t.join();
      }
    } pool{{}, stop};
    for (int t = 1; t < count; ++t) pool.threads.emplace_back(work, false);
    work(true);
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  context.check_cancel();
  if (!stage.empty()) context.report(stage, 1.0);
}

/// parallel_for on context.threads threads (0: one per hardware thread).
template <class F>
void parallel_for(int n, const Context& context, F&& body, const std::string& stage = {}) {
  parallel_for(n, 0, context, std::forward<F>(body), stage);
}

}  // namespace qs
