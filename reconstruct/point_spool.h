// Oriented points on disk, one fixed-size record each in input order, for
// builds whose points do not fit in memory beside their work. The inputs
// stream in file by file; what the brick plan needs of the whole set (count,
// bounds, the attributes present, a hash of every record) is gathered on the
// way, and the records are read back a buffer at a time.
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace scan2lod {

// One point as the spool and the brick bins hold it. Attributes a part lacks
// carry OrientedPoints::append()'s fill values, so a record is the same
// whether its part came alone or merged.
struct PointRecord {
  Vec3f position;
  Vec3f normal;
  float confidence;
  float spacing;
  std::uint32_t index;  // in input order: bricks gather their points back into it
  Rgb color;
  std::uint8_t unused;  // zero: records are hashed byte by byte
};
static_assert(sizeof(PointRecord) == 40, "records are written as they lie in memory");

struct PointCensus {
  std::size_t count = 0;
  Aabb box;
  bool colors = false, confidence = false, spacing = false;  // present in some part
  std::uint64_t hash = 0;  // of every record, in order
};

// Visits records a buffer at a time, in order.
using RecordVisitor = std::function<void(const PointRecord*, std::size_t)>;

class CensusTaker;

class PointSpool {
 public:
  // Creates (or empties) the file at `path`; it is removed with the spool.
  explicit PointSpool(std::string path);
  ~PointSpool();
  PointSpool(const PointSpool&) = delete;
  PointSpool& operator=(const PointSpool&) = delete;

  // Appends a part's points. Throws InputError for a point with a non-finite
  // position or normal (naming its index), past 2^32 points, and when the
  // disk refuses the write.
  void add(const OrientedPoints& part);
  // Ends writing; reading may start. The census is final from here.
  void close();

  const PointCensus& census() const;  // final once closed
  const std::string& path() const { return path_; }

  // Under a job of several processes each spools a share of the points (the
  // files it read): the job's points are the shares in rank order. `job` is
  // their census, and this share's first record is the job's point `first`.
  // Unset, the spool holds every point.
  void join(const PointCensus& job, std::size_t first);
  bool shared() const { return shared_; }
  const PointCensus& job_census() const { return shared_ ? job_ : census(); }
  std::size_t first() const { return first_; }

  // Calls visit(records, n) over all records in order, a buffer at a time.
  void for_each(const RecordVisitor& visit) const;

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  PointCensus census_;                  // once closed
  std::unique_ptr<CensusTaker> taker_;  // while writing
  bool shared_ = false;
  PointCensus job_;
  std::size_t first_ = 0;
};

// Calls visit(records, n) over the `count` records of a closed spool's file,
// a buffer at a time: a spool another process of the job wrote.
void for_each_spooled(const std::string& path, std::size_t count, const RecordVisitor& visit);

// The census as bytes between the processes of a job, and back.
std::string census_bytes(const PointCensus& census);
PointCensus census_from_bytes(const std::string& bytes);
// The census of the shares' points taken together, in order. One share's is
// its own; the hash of several is one over theirs.
PointCensus merge_censuses(const std::vector<PointCensus>& shares);

// The records of points in memory, as a spool of them would hold them.
void for_each_record(const OrientedPoints& points, const RecordVisitor& visit);
// The census of points in memory, as a spool of them would take it.
PointCensus census_of(const OrientedPoints& points);

// Records back into points, with the census's attributes (those absent from
// every part stay empty, as in a merged OrientedPoints).
void append_records(const PointRecord* records, std::size_t n, const PointCensus& census, OrientedPoints* points);

}  // namespace scan2lod
