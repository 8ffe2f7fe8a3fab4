// A run's outputs as one tar file (TarLayout), streamed by the server without holding it in memory.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "qs/studio/studio.h"
#include "qs/studio/studio_detail.h"

namespace qs::studio {

using namespace detail;

namespace {

constexpr size_t kBlock = 512;

size_t padded(size_t n) { return (n + kBlock - 1) / kBlock * kBlock; }

/// An octal field of `width` bytes (digits, then NUL), as ustar writes numbers.
void put_octal(std::string& h, size_t at, size_t width, unsigned long long v) {
  for (size_t k = width - 1; k-- > 0; v >>= 3) h[at + k] = static_cast<char>('0' + (v & 7));
  h[at + width - 1] = '\0';
}

/// One 512-byte header: `name` (at most 100 bytes), a regular file ('0') or a GNU long name ('L').
std::string header(const std::string& name, unsigned long long size, long long mtime, char type) {
  std::string h(kBlock, '\0');
  std::memcpy(&h[0], name.data(), std::min<size_t>(name.size(), 100));
  put_octal(h, 100, 8, 0644);
  put_octal(h, 108, 8, 0);
  put_octal(h, 116, 8, 0);
  put_octal(h, 124, 12, size);
  put_octal(h, 136, 12, static_cast<unsigned long long>(std::max<long long>(mtime, 0)));
  h[156] = type;
  std::memcpy(&h[257], "ustar", 6);  // "ustar\0" then version "00"
  h[263] = '0', h[264] = '0';
  std::memset(&h[148], ' ', 8);  // the checksum counts its own field as spaces
  unsigned sum = 0;
  for (unsigned char c : h) sum += c;
  put_octal(h, 148, 7, sum);  // six digits, NUL, then the space already there

  return h;
}

}  // namespace

TarLayout::TarLayout(const std::vector<std::pair<std::string, fs::path>>& files) {
  auto add = [&](Segment s) {
    s.begin = size_;
    if (s.file.empty()) s.size = s.bytes.size();
    size_ += s.size;
    if (s.size) segments_.push_back(std::move(s));
  };
  for (const auto& [name, file] : files) {
    struct stat st {};
    if (stat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      throw IoError("cannot read " + quote(name) + " for the archive");
    const auto bytes = static_cast<size_t>(st.st_size);
    if (bytes >= (1ull << 33)) throw IoError(quote(name) + " is too large for the archive (8 GiB or more)");
    if (name.size() > 100) {
      // GNU tar's long name: a record named ././@LongLink holding the name (NUL-terminated).
      std::string data = name + '\0';
      add({0, 0, header("././@LongLink", data.size(), 0, 'L'), {}});
      data.resize(padded(data.size()), '\0');
      add({0, 0, data, {}});
    }
    add({0, 0, header(name, bytes, static_cast<long long>(st.st_mtime), '0'), {}});
    add({0, bytes, {}, file});
    add({0, 0, std::string(padded(bytes) - bytes, '\0'), {}});
  }
  add({0, 0, std::string(2 * kBlock, '\0'), {}});  // the end: two zero blocks
}

size_t TarLayout::read(size_t offset, char* out, size_t n) const {
  auto it = std::upper_bound(segments_.begin(), segments_.end(), offset,
                             [](size_t o, const Segment& s) { return o < s.begin; });
  if (it == segments_.begin()) return 0;
  --it;
  if (offset >= it->begin + it->size) return 0;
  const size_t at = offset - it->begin, take = std::min(n, it->size - at);
  if (it->file.empty()) {
    std::memcpy(out, it->bytes.data() + at, take);
    return take;
  }
  const int fd = open(it->file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  ssize_t got;
  while ((got = pread(fd, out, take, static_cast<off_t>(at))) < 0 && errno == EINTR) {
  }
  close(fd);
  return got > 0 ? static_cast<size_t>(got) : 0;
}

}  // namespace qs::studio
