#include <scan2lod/reconstruct/point_spool.h>

#include <scan2lod/core/error.h>
#include <scan2lod/distributed/message.h>

#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace scan2lod {
namespace {

constexpr std::size_t kBufferRecords = 1 << 16;  // 2.5 MiB, reused

// The records of part's points [from, to), numbered from `first` on.
void pack(const OrientedPoints& part, std::size_t first, std::size_t from, std::size_t to,
          std::vector<PointRecord>* out) {
  const std::size_t n = part.size();
  const bool colors = part.colors.size() == n, confidence = part.confidence.size() == n,
             spacing = part.spacing.size() == n;
  out->clear();
  for (std::size_t i = from; i < to; ++i) {
    if (!part.positions[i].allFinite() || !part.normals[i].allFinite())
      throw InputError("", "input point " + std::to_string(first + i) + " has non-finite coordinates or normal");
    PointRecord r;
    r.position = part.positions[i];
    r.normal = part.normals[i];
    r.confidence = confidence ? part.confidence[i] : 1.0f;
    r.spacing = spacing ? part.spacing[i] : 0.0f;
    r.index = std::uint32_t(first + i);
    r.color = colors ? part.colors[i] : Rgb{200, 200, 200};
    r.unused = 0;
    out->push_back(r);
  }
}

void count_part(const OrientedPoints& part, PointCensus* census) {
  const std::size_t n = part.size();
  if (census->count + n >= (std::size_t(1) << 32))
    throw InputError("", "more than 2^32 points in one build: split the input");
  census->colors |= part.colors.size() == n && n > 0;
  census->confidence |= part.confidence.size() == n && n > 0;
  census->spacing |= part.spacing.size() == n && n > 0;
}

}  // namespace

// The census taken part by part: each part packed a buffer at a time, the
// buffers hashed and handed on (to the spool's file, or nowhere).
class CensusTaker {
 public:
  CensusTaker() : hash_(XXH3_createState()) { XXH3_64bits_reset(hash_); }
  ~CensusTaker() { XXH3_freeState(hash_); }
  CensusTaker(const CensusTaker&) = delete;
  CensusTaker& operator=(const CensusTaker&) = delete;

  template <class Sink>
  void add(const OrientedPoints& part, Sink sink) {
    count_part(part, &census_);
    for (std::size_t i = 0; i < part.size(); i += kBufferRecords) {
      pack(part, census_.count, i, std::min(part.size(), i + kBufferRecords), &buffer_);
      for (const PointRecord& r : buffer_) census_.box.extend(r.position);
      XXH3_64bits_update(hash_, buffer_.data(), buffer_.size() * sizeof(PointRecord));
      sink(buffer_);
    }
    census_.count += part.size();
  }
  const PointCensus& census() const { return census_; }
  PointCensus finish() {
    census_.hash = XXH3_64bits_digest(hash_);
    return census_;
  }

 private:
  XXH3_state_t* hash_;
  PointCensus census_;
  std::vector<PointRecord> buffer_;
};

PointSpool::PointSpool(std::string path) : path_(std::move(path)), taker_(std::make_unique<CensusTaker>()) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
}

PointSpool::~PointSpool() {
  if (file_) std::fclose(file_);
  std::error_code ec;
  std::filesystem::remove(path_, ec);
}

const PointCensus& PointSpool::census() const { return taker_ ? taker_->census() : census_; }

void PointSpool::add(const OrientedPoints& part) {
  if (!taker_) throw std::logic_error("PointSpool::add after close");
  taker_->add(part, [&](const std::vector<PointRecord>& buffer) {
    if (std::fwrite(buffer.data(), sizeof(PointRecord), buffer.size(), file_) != buffer.size())
      throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
  });
}

void PointSpool::close() {
  if (!taker_) return;
  if (std::fflush(file_) != 0 || std::ferror(file_))
    throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
  std::fclose(file_);
  file_ = nullptr;
  census_ = taker_->finish();
  taker_.reset();
}

void PointSpool::for_each(const RecordVisitor& visit) const {
  if (taker_) throw std::logic_error("PointSpool::for_each before close");
  for_each_spooled(path_, census_.count, visit);
}

void PointSpool::join(const PointCensus& job, std::size_t first) {
  if (taker_) throw std::logic_error("PointSpool::join before close");
  shared_ = true, job_ = job, first_ = first;
}

void for_each_spooled(const std::string& path, std::size_t count, const RecordVisitor& visit) {
  std::FILE* in = std::fopen(path.c_str(), "rb");
  if (!in) throw InputError(path, "the point spool vanished: " + std::string(std::strerror(errno)));
  std::vector<PointRecord> buffer(kBufferRecords);
  std::size_t total = 0;
  for (;;) {
    const std::size_t n = std::fread(buffer.data(), sizeof(PointRecord), buffer.size(), in);
    if (n == 0) break;
    total += n;
    visit(buffer.data(), n);
  }
  std::fclose(in);
  if (total != count)
    throw InputError(path, "the point spool changed during the build: " + std::to_string(total) + " points of " +
                               std::to_string(count));
}

std::string census_bytes(const PointCensus& c) {
  MessageWriter out;
  out.put(std::uint64_t(c.count));
  for (const Vec3f* v : {&c.box.min, &c.box.max}) out.put(v->x()), out.put(v->y()), out.put(v->z());
  out.put(std::uint8_t(c.colors | c.confidence << 1 | c.spacing << 2));
  out.put(c.hash);
  return std::move(out.bytes());
}

PointCensus census_from_bytes(const std::string& bytes) {
  MessageReader in(bytes);
  PointCensus c;
  std::uint64_t count = 0;
  std::uint8_t flags = 0;
  in.get(&count);
  for (Vec3f* v : {&c.box.min, &c.box.max}) in.get(&v->x()), in.get(&v->y()), in.get(&v->z());
  in.get(&flags), in.get(&c.hash);
  if (!in.done()) throw std::runtime_error("a point census between ranks is longer than expected");
  c.count = std::size_t(count);
  c.colors = flags & 1, c.confidence = flags & 2, c.spacing = flags & 4;
  return c;
}

PointCensus merge_censuses(const std::vector<PointCensus>& shares) {
  if (shares.size() == 1) return shares.front();
  PointCensus job;
  XXH3_state_t* hash = XXH3_createState();
  XXH3_64bits_reset(hash);
  for (const PointCensus& s : shares) {
    job.count += s.count;
    if (!s.box.empty()) job.box.extend(s.box.min), job.box.extend(s.box.max);
    job.colors |= s.colors, job.confidence |= s.confidence, job.spacing |= s.spacing;
    const std::uint64_t part[2] = {s.hash, std::uint64_t(s.count)};
    XXH3_64bits_update(hash, part, sizeof part);
  }
  job.hash = XXH3_64bits_digest(hash);
  XXH3_freeState(hash);
  if (job.count >= (std::size_t(1) << 32)) throw InputError("", "more than 2^32 points in one build: split the input");
  return job;
}

void for_each_record(const OrientedPoints& points, const RecordVisitor& visit) {
  std::vector<PointRecord> buffer;
  buffer.reserve(std::min(points.size(), kBufferRecords));
  for (std::size_t i = 0; i < points.size(); i += kBufferRecords) {
    pack(points, 0, i, std::min(points.size(), i + kBufferRecords), &buffer);
    visit(buffer.data(), buffer.size());
  }
}

PointCensus census_of(const OrientedPoints& points) {
  CensusTaker taker;
  taker.add(points, [](const std::vector<PointRecord>&) {});
  return taker.finish();
}

void append_records(const PointRecord* records, std::size_t n, const PointCensus& census, OrientedPoints* points) {
  for (std::size_t i = 0; i < n; ++i) {
    const PointRecord& r = records[i];
    points->positions.push_back(r.position);
    points->normals.push_back(r.normal);
    if (census.colors) points->colors.push_back(r.color);
    if (census.confidence) points->confidence.push_back(r.confidence);
    if (census.spacing) points->spacing.push_back(r.spacing);
  }
}

}  // namespace scan2lod
