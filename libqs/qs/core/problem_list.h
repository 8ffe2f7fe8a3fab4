#pragma once
// Collects the problems of one kind for an error message and renders them as
// "what: id, id, ... (and N more)", listing at most `max_listed` items.

#include <cstddef>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace qs {

class ProblemList {
 public:
  explicit ProblemList(std::string what, int max_listed = 8) : what_(std::move(what)), max_listed_(max_listed) {}
  void add(const std::string& item) {
    if (count_ < max_listed_) items_.push_back(item);
    ++count_;
  }
  bool empty() const { return count_ == 0; }
  /// Appends the rendered line to `out` when anything was added.
  void append_to(std::vector<std::string>& out) const {
    if (count_ == 0) return;
    std::ostringstream s;
    s << what_ << ": ";
    for (std::size_t i = 0; i < items_.size(); ++i) s << (i ? ", " : "") << items_[i];
    if (count_ > static_cast<int>(items_.size())) s << " (and " << count_ - items_.size() << " more)";
    out.push_back(s.str());
  }

 private:
  std::string what_;
  int max_listed_;
  std::vector<std::string> items_;
  int count_ = 0;
};

}  // namespace qs
