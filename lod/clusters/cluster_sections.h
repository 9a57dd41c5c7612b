// The cluster hierarchy's part of the model file (lod/model_sections.h;
// lod/model_file.h lists its sections): its info record, clusters, triangles
// (from memory or a spool), groups, pages, and from format 4.6 each page's
// geometry (lod/clusters/page_geometry.h), with the checks that keep a cut in
// bounds. read_model_pages_head reads it without the triangles. Internal.
#pragma once

#include <scan2lod/lod/clusters/page_geometry.h>
#include <scan2lod/lod/model_sections.h>

#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

class ClusterSections final : public StructureSections {
 public:
  std::vector<SectionRow> rows() override;
  void prepare(const LodModel& model, std::uint32_t major) override;
  bool in(const SectionReader& file) const override { return file.major() >= 3 && file.has("CINF"); }
  std::string mark() const override { return "clusters ('CINF')"; }
  void decode(SectionReader& file, LodModel* model) override;

  // After decode(): 'PGIX' must lay the pages end to end over 'PGEO', each
  // within what its triangles can need, with a finite box.
  void check_page_extents(const SectionReader& file, const ClusterHierarchy& h) const;
  std::vector<PageExtent>& page_extents() { return page_extents_; }

 private:
  const LodModel* model_ = nullptr;       // writer: whose pages 'PGEO' encodes
  std::uint64_t info_[3] = {0, 0, 0};     // 'CINF'
  std::vector<PageExtent> page_extents_;  // 'PGIX'
  std::uint64_t page_bytes_ = 0;          // 'PGEO''s length, streamed (never held whole)
  std::uint64_t pages_checksum_ = 0;
  bool with_pages_ = false;               // writer: 'PGIX' and 'PGEO' are written
  bool paged_ = false;                    // reader: 'CTRI' stays in the file
};

}  // namespace scan2lod
