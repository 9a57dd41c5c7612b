// libFuzzer target for the .mco reader: whatever decode_model accepts must
// extract (extract_lod, compact_lod, LodCursor) without reading out of bounds.
// Built only with clang (tests/fuzz/build.sh), under AddressSanitizer and UBSan.
//
// An input is either
// - 'R' + a whole file, whose checksums are recomputed first so that the
//   damage reaches the structure checks behind them, or
// - 'S' + edits of 9 bytes (array, index, value) applied to a seed model,
//   which is then encoded (correct checksums) and read back: damage that is
//   consistent at the byte level and wrong in meaning.
// The seed model is $MODEL_FUZZ_SEED (a small .mco, e.g. the bunny at R = 16).
#include "core/error.h"
#include "lod/extract.h"
#include "lod/lod_cursor.h"
#include "lod/model_file.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

using namespace scan2lod;

namespace {

std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
void put_u64(std::uint8_t* p, std::uint64_t v) { std::memcpy(p, &v, 8); }

// Recomputes every checksum the layout lets us find (model_file.h).
void fix_checksums(std::vector<std::uint8_t>& b) {
  constexpr std::size_t kHeader = 40, kEntry = 48;
  if (b.size() < kHeader + 8) return;
  put_u64(&b[32], model_checksum(b.data(), 32));
  std::uint32_t count;
  std::memcpy(&count, &b[16], 4);
  if (count > 4096 || kHeader + kEntry * std::size_t(count) + 8 > b.size()) return;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint8_t* e = &b[kHeader + kEntry * i];
    const std::uint64_t offset = get_u64(e + 24), length = get_u64(e + 32);
    if (offset <= b.size() && length <= b.size() - offset) put_u64(e + 40, model_checksum(b.data() + offset, length));
  }
  put_u64(&b[kHeader + kEntry * count], model_checksum(&b[kHeader], kEntry * count));
  put_u64(&b[b.size() - 8], model_checksum(b.data(), b.size() - 8));
}

const LodModel& seed() {
  static const LodModel model = [] {
    const char* path = std::getenv("MODEL_FUZZ_SEED");
    if (!path) {
      std::fprintf(stderr, "model_fuzzer: set MODEL_FUZZ_SEED to a small .mco\n");
      std::abort();
    }
    return load_model(path);
  }();
  return model;
}

template <class T>
void edit(std::vector<T>& v, std::uint32_t index, std::uint32_t value) {
  if (v.empty()) return;
  auto* words = reinterpret_cast<std::uint8_t*>(v.data());
  const std::size_t bytes = v.size() * sizeof(T);
  // Values near the edges are the interesting ones: small, negative, huge.
  const std::int32_t signed_value = std::int32_t(value);
  const std::size_t width = sizeof(T) % 4 == 0 ? 4 : 1;
  const std::size_t at = (std::size_t(index) * width) % bytes / width * width;
  if (width == 4) std::memcpy(words + at, &signed_value, 4);
  else words[at] = std::uint8_t(value);
}

void apply(LodModel& m, const std::uint8_t* op) {
  std::uint32_t index, value;
  std::memcpy(&index, op + 1, 4);
  std::memcpy(&value, op + 5, 4);
  McOctree& t = m.tree;
  switch (op[0] % 26) {
    case 0: edit(t.keys, index, value); break;
    case 1: edit(t.levels, index, value); break;
    case 2: edit(t.parents, index, value); break;
    case 3: edit(t.first_child, index, value); break;
    case 4: edit(t.child_counts, index, value); break;
    case 5: edit(t.cases, index, value); break;
    case 6: edit(t.edge_vertices, index, value); break;
    case 7: edit(t.first_triangle, index, value); break;
    case 8: edit(t.triangle_counts, index, value); break;
    case 9: edit(t.metrics, index, value); break;
    case 10: edit(t.boundary_inside, index, value); break;
    case 11: edit(t.sub_edge_vertices, index, value); break;
    case 12: edit(t.centre_vertices, index, value); break;
    case 13: edit(t.neighbours, index, value); break;
    case 14: edit(t.triangles, index, value); break;
    case 15: edit(t.patch_triangles, index, value); break;
    case 16: edit(t.patch_group_first, index, value); break;
    case 17: edit(t.patch_needs_first, index, value); break;
    case 18: edit(t.patch_needs, index, value); break;
    case 19: edit(t.positions, index, value); break;
    case 20: edit(m.lod.order, index, value); break;
    case 21: edit(m.lod.accumulated, index, value); break;
    case 22: m.lod.pinned = value; break;
    case 23: t.grid.resolution = std::int32_t(value); break;
    case 24: t.depth = std::int32_t(value); break;
    case 25: t.mesh_vertices = value; break;
  }
}

void extract_everything(const LodModel& m) {
  std::vector<std::uint8_t> flags;
  std::vector<Triangle> triangles;
  const std::size_t full = m.lod.full();
  for (const std::size_t p : {std::size_t(0), m.lod.pinned, full / 3, full / 2, full}) {
    extract_lod(m.tree, m.lod, p, &flags, &triangles);
    compact_lod(m.tree, triangles);
  }
  LodCursor cursor(m.tree, m.lod);
  for (const std::size_t p : {full, full / 2, std::size_t(1), full / 3 + 1, std::size_t(0)}) cursor.move_to(p);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::vector<std::uint8_t> bytes;
  if (data[0] == 'S') {
    LodModel m = seed();
    for (std::size_t at = 1; at + 9 <= size; at += 9) apply(m, data + at);
    bytes = encode_model(m);
  } else if (data[0] == 'R') {
    bytes.assign(data + 1, data + size);
    fix_checksums(bytes);
  } else {
    return 0;
  }
  try {
    const LodModel model = decode_model(bytes.data(), bytes.size(), "fuzz.mco");
    extract_everything(model);
  } catch (const InputError&) {
  }
  return 0;
}
