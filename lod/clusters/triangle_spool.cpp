#include <scan2lod/lod/clusters/triangle_spool.h>

#include <scan2lod/core/error.h>

#include <fcntl.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstring>

namespace scan2lod {

namespace {
constexpr std::size_t kRun = std::size_t(1) << 16;  // triangles a write or a read moves: 768 KiB
}

struct TriangleSpool::Hash {
  XXH64_state_t* state = XXH64_createState();
  ~Hash() { XXH64_freeState(state); }
};

TriangleSpool::TriangleSpool(std::string path) : path_(std::move(path)), hash_(new Hash) {
  if (!hash_->state) throw std::bad_alloc();
  XXH64_reset(hash_->state, 0);
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd_ < 0) throw InputError(path_, std::string("cannot create the triangle spool: ") + std::strerror(errno));
  buffer_.reserve(kRun);
}

TriangleSpool::~TriangleSpool() {
  if (fd_ >= 0) ::close(fd_);
  ::unlink(path_.c_str());
}

void TriangleSpool::append(const Triangle* triangles, std::size_t count) {
  XXH64_update(hash_->state, triangles, count * sizeof(Triangle));
  count_ += count;
  while (count > 0) {
    const std::size_t n = std::min(count, kRun - buffer_.size());
    buffer_.insert(buffer_.end(), triangles, triangles + n);
    triangles += n;
    count -= n;
    if (buffer_.size() == kRun) flush();
  }
}

void TriangleSpool::flush() const {
  const auto* p = reinterpret_cast<const char*>(buffer_.data());
  std::size_t left = buffer_.size() * sizeof(Triangle);
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw InputError(path_, std::string("cannot write the triangle spool: ") +
                                  (n < 0 ? std::strerror(errno) : "no space written"));
    p += n;
    left -= std::size_t(n);
  }
  buffer_.clear();
}

std::uint64_t TriangleSpool::checksum() const { return XXH64_digest(hash_->state); }

void TriangleSpool::read(const std::function<void(const std::uint8_t*, std::size_t)>& out) const {
  flush();
  std::vector<std::uint8_t> run(kRun * sizeof(Triangle));
  const std::uint64_t bytes = count_ * sizeof(Triangle);
  for (std::uint64_t at = 0; at < bytes;) {
    const std::size_t want = std::size_t(std::min<std::uint64_t>(run.size(), bytes - at));
    const ssize_t n = ::pread(fd_, run.data(), want, off_t(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw InputError(path_, std::string("cannot read the triangle spool back: ") +
                                  (n < 0 ? std::strerror(errno) : "the file is shorter than written"));
    out(run.data(), std::size_t(n));
    at += std::uint64_t(n);
  }
}

std::vector<Triangle> TriangleSpool::load() const {
  std::vector<Triangle> all(count_);
  auto* to = reinterpret_cast<std::uint8_t*>(all.data());
  read([&](const std::uint8_t* p, std::size_t n) {
    std::memcpy(to, p, n);
    to += n;
  });
  return all;
}

}  // namespace scan2lod
