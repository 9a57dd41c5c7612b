#include "reconstruct/point_spool.h"

#include "core/error.h"

#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <algorithm>
#include <limits>
#include <stdexcept>

namespace scan2lod {
namespace {

constexpr std::size_t kBufferRecords = 1 << 16;  // 2.5 MiB, reused

XXH3_state_t* state(void* p) { return static_cast<XXH3_state_t*>(p); }

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

PointSpool::PointSpool(std::string path) : path_(std::move(path)) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
  hash_state_ = XXH3_createState();
  XXH3_64bits_reset(state(hash_state_));
  buffer_.reserve(kBufferRecords);
}

PointSpool::~PointSpool() {
  if (file_) std::fclose(file_);
  if (hash_state_) XXH3_freeState(state(hash_state_));
  std::error_code ec;
  std::filesystem::remove(path_, ec);
}

void PointSpool::add(const OrientedPoints& part) {
  if (!hash_state_) throw std::logic_error("PointSpool::add after close");
  count_part(part, &census_);
  for (std::size_t i = 0; i < part.size(); i += kBufferRecords) {
    pack(part, census_.count, i, std::min(part.size(), i + kBufferRecords), &buffer_);
    for (const PointRecord& r : buffer_) census_.box.extend(r.position);
    XXH3_64bits_update(state(hash_state_), buffer_.data(), buffer_.size() * sizeof(PointRecord));
    if (std::fwrite(buffer_.data(), sizeof(PointRecord), buffer_.size(), file_) != buffer_.size())
      throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
  }
  census_.count += part.size();
}

void PointSpool::close() {
  if (!hash_state_) return;
  if (std::fflush(file_) != 0 || std::ferror(file_))
    throw InputError(path_, "cannot write the point spool: " + std::string(std::strerror(errno)));
  std::fclose(file_);
  file_ = nullptr;
  census_.hash = XXH3_64bits_digest(state(hash_state_));
  XXH3_freeState(state(hash_state_));
  hash_state_ = nullptr;
  buffer_ = std::vector<PointRecord>();
}

void PointSpool::for_each(const RecordVisitor& visit) const {
  if (hash_state_) throw std::logic_error("PointSpool::for_each before close");
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
  PointCensus census;
  count_part(points, &census);
  XXH3_state_t* hash = XXH3_createState();
  XXH3_64bits_reset(hash);
  for_each_record(points, [&](const PointRecord* r, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) census.box.extend(r[i].position);
    XXH3_64bits_update(hash, r, n * sizeof(PointRecord));
  });
  census.hash = XXH3_64bits_digest(hash);
  XXH3_freeState(hash);
  census.count = points.size();
  return census;
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
