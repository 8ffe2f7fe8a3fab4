#pragma once
// A loop over 0..n-1 on a few threads, for the library's parallel passes.

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "qs/core/context.h"

namespace qs {

/// Calls body(i) for i in [0, n) on min(threads, n) threads (threads <= 0: all cores), items taken
/// in order as threads come free. The first exception a body throws stops the loop and is
/// rethrown here; a raised cancel flag stops it too (Error(Internal "cancelled"), from
/// context.check_cancel()). Results that depend only on i do not depend on the thread count.
template <class F>
void parallel_for(int n, int threads, const Context& context, F&& body) {
  threads = std::max(1, std::min(threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency()), n));
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (int i; (i = next++) < n;) {
      if (failed || (context.cancel && context.cancel->load())) return;
      try {
        body(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  context.check_cancel();
}

}  // namespace qs
