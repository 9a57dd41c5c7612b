#include "reconstruct/point_spool.h"

#include "core/error.h"

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
  std::FILE* in = std::fopen(path_.c_str(), "rb");
  if (!in) throw InputError(path_, "the point spool vanished: " + std::string(std::strerror(errno)));
  std::vector<PointRecord> buffer(kBufferRecords);
  std::size_t total = 0;
  for (;;) {
    const std::size_t n = std::fread(buffer.data(), sizeof(PointRecord), buffer.size(), in);
    if (n == 0) break;
    total += n;
    visit(buffer.data(), n);
  }
  std::fclose(in);
  if (total != census_.count)
    throw InputError(path_, "the point spool changed during the build: " + std::to_string(total) + " points of " +
                                std::to_string(census_.count));
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
