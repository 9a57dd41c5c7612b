#include <scan2lod/lod/octree/lod_cursor.h>

#include <scan2lod/lod/octree/extract.h>

#include <algorithm>
#include <cassert>

namespace scan2lod {
namespace {

// flags_ bits: emit_node reads bit 0 alone, so bit 1 can mark nodes to re-emit
// (the values mark_cut writes).
constexpr std::uint8_t kDirty = 2;

// slot_owner_ beyond block ids.
constexpr std::int32_t kHole = -1, kInside = -2;

// A move rebuilds the cut when that cut has fewer than this many nodes per
// expansion or collapse. A re-emitted node (its data scattered over the tree)
// costs several rebuilt ones (in node order): on the bunny at R = 256 the
// changes cost as much as a rebuild at 30 to 190 cut nodes per change, by level.
constexpr std::size_t kRebuildRatio = 32;

}  // namespace

LodCursor::LodCursor(const McOctree& tree, const LodArray& lod) : tree_(&tree), lod_(&lod) {
  assert(tree.size() > 0);
  const std::size_t nodes = tree.size(), groups = tree.patch_groups();
  flags_.assign(nodes, 0);
  block_first_.assign(nodes + groups, 0);
  block_count_.assign(nodes + groups, 0);

  needs_left_.resize(groups);
  need_groups_first_.assign(nodes + 1, 0);
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1]; ++k)
      ++need_groups_first_[std::size_t(tree.patches.needs[k]) + 1];
  }
  for (std::size_t n = 0; n < nodes; ++n) need_groups_first_[n + 1] += need_groups_first_[n];
  need_groups_.resize(std::size_t(need_groups_first_[nodes]));
  std::vector<std::int32_t> next(need_groups_first_.begin(), need_groups_first_.end() - 1);
  for (std::size_t g = 0; g < groups; ++g)
    for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1]; ++k)
      need_groups_[std::size_t(next[std::size_t(tree.patches.needs[k])]++)] = std::int32_t(g);

  rebuild(0);
}

void LodCursor::move_to(std::size_t priority) {
  priority = std::min(priority, lod_->full());
  emitted_last_move_ = 0;
  rebuilt_last_move_ = false;
  // The cut the move lands on: an expansion trades a node for its children.
  const std::size_t changes = priority > priority_ ? priority - priority_ : priority_ - priority;
  std::size_t cut = cut_nodes_;
  for (std::size_t i = std::min(priority, priority_); i < std::max(priority, priority_); ++i) {
    const std::size_t children = tree_->nodes.child_counts[std::size_t(lod_->order[i])];
    cut = priority > priority_ ? cut + children - 1 : cut - children + 1;
  }
  if (cut < kRebuildRatio * changes) {
    rebuild(priority);
    rebuilt_last_move_ = true;
    return;
  }
  cut_nodes_ = cut;
  while (priority_ < priority) expand(lod_->order[priority_++]);
  while (priority_ > priority) collapse(lod_->order[--priority_]);
  // Only now are all flags final, which the transitions of the nodes read.
  // The dirty nodes lie all over the tree: what each reads is asked for a few
  // nodes ahead.
  constexpr std::size_t kAhead = 8;
  for (std::size_t i = 0; i < dirty_.size(); ++i) {
    if (i + kAhead < dirty_.size()) prefetch(dirty_[i + kAhead]);
    const std::int32_t node = dirty_[i];
    flags_[std::size_t(node)] &= std::uint8_t(~kDirty);
    if (in_cut(node))
      emit(node);
    else
      remove(node);
  }
  dirty_.clear();
  if (4 * holes_ > buffer_.size()) compact();
}

void LodCursor::live_triangles(std::vector<Triangle>* triangles) const {
  triangles->clear();
  triangles->reserve(buffer_.size() - holes_);
  for (std::size_t i = 0; i < buffer_.size(); ++i)
    if (slot_owner_[i] != kHole) triangles->push_back(buffer_[i]);
}

void LodCursor::rebuild(std::size_t priority) {
  const McOctree& tree = *tree_;
  // Drops every block, through the old buffer's block starts when it is the shorter.
  if (slot_owner_.size() < block_count_.size()) {
    for (const std::int32_t owner : slot_owner_)
      if (owner >= 0) block_count_[std::size_t(owner)] = 0;
  } else {
    std::fill(block_count_.begin(), block_count_.end(), 0);
  }
  buffer_.clear();
  slot_owner_.clear();
  holes_ = 0;
  // The cut as extract_lod finds it (mark_cut's 2 is kDirty), then emitted in
  // node order, where neighbouring nodes' data sit together.
  std::fill(flags_.begin(), flags_.end(), 0);
  mark_cut(tree, *lod_, priority, flags_.data());
  priority_ = priority;
  cut_.clear();
  emit_cut(tree, flags_, &buffer_, &cut_);
  slot_owner_.assign(buffer_.size(), kInside);  // one fill rather than one per block
  std::size_t first = 0;
  for (const CutBlock& b : cut_) {
    const std::size_t node = std::size_t(b.node);
    flags_[node] = 0;
    block_first_[node] = first;
    block_count_[node] = b.count;
    if (b.count) slot_owner_[first] = b.node;
    first += std::size_t(b.count);
  }
  cut_nodes_ = cut_.size();
  emitted_last_move_ += cut_nodes_;
  for (std::size_t g = 0; g < needs_left_.size(); ++g) {
    std::int32_t left = 0;
    for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1]; ++k)
      left += !(flags_[std::size_t(tree.patches.needs[k])] & kExpanded);
    needs_left_[g] = left;
    if (left == 0) append_group(g);
  }
}

void LodCursor::expand(std::int32_t node) {
  assert(in_cut(node) && !tree_->is_leaf(std::size_t(node)));  // the LOD array expands parents first
  flags_[std::size_t(node)] |= kExpanded;
  mark_around(node);
  for (std::int32_t k = need_groups_first_[std::size_t(node)]; k < need_groups_first_[std::size_t(node) + 1]; ++k) {
    const std::size_t g = std::size_t(need_groups_[std::size_t(k)]);
    if (--needs_left_[g] == 0) append_group(g);
  }
}

void LodCursor::collapse(std::int32_t node) {
  assert(flags_[std::size_t(node)] & kExpanded);
  flags_[std::size_t(node)] &= std::uint8_t(~kExpanded);
  mark_around(node);
  for (std::int32_t k = need_groups_first_[std::size_t(node)]; k < need_groups_first_[std::size_t(node) + 1]; ++k) {
    const std::size_t g = std::size_t(need_groups_[std::size_t(k)]);
    if (needs_left_[g]++ == 0) remove(std::int32_t(tree_->size() + g));
  }
}

void LodCursor::prefetch(std::int32_t node) const {
  const std::size_t n = std::size_t(node);
  __builtin_prefetch(&tree_->nodes.parents[n]);
  __builtin_prefetch(&block_count_[n]);
  __builtin_prefetch(&block_first_[n]);
  prefetch_node(*tree_, node);
}

void LodCursor::mark(std::int32_t node) {
  std::uint8_t& f = flags_[std::size_t(node)];
  if (f & kDirty) return;
  f |= kDirty;
  dirty_.push_back(node);
}

// What a node's change of state can alter: whether it and its children are in
// the cut, and the transitions of its same-level neighbours across a face or an
// edge, the only nodes whose triangles its flag decides (McOctree::neighbours
// is symmetric: a lattice offset).
void LodCursor::mark_around(std::int32_t node) {
  const std::size_t n = std::size_t(node);
  mark(node);
  for (std::int32_t c = tree_->nodes.first_child[n], end = c + tree_->nodes.child_counts[n]; c < end; ++c) mark(c);
  const auto& around = tree_->transitions.neighbours[n];  // expanded nodes are internal
  for (const int c : splitting_cells())
    if (around[std::size_t(c)] >= 0) mark(around[std::size_t(c)]);
}

bool LodCursor::in_cut(std::int32_t node) const {
  const std::int32_t parent = tree_->nodes.parents[std::size_t(node)];
  return !(flags_[std::size_t(node)] & kExpanded) && (parent < 0 || (flags_[std::size_t(parent)] & kExpanded));
}

void LodCursor::emit(std::int32_t node) {
  emitted_.clear();
  emit_node(*tree_, node, flags_, &emitted_);
  ++emitted_last_move_;
  std::int32_t& count = block_count_[std::size_t(node)];
  if (count != 0 && std::size_t(count) == emitted_.size()) {
    // As many as before (a neighbour's change often leaves the count alone):
    // overwritten where they were, leaving no hole.
    std::copy(emitted_.begin(), emitted_.end(), buffer_.begin() + std::ptrdiff_t(block_first_[std::size_t(node)]));
    return;
  }
  remove(node);
  const std::size_t end = buffer_.size();
  buffer_.insert(buffer_.end(), emitted_.begin(), emitted_.end());
  place(node, end);
}

void LodCursor::append_group(std::size_t group) {
  const std::size_t end = buffer_.size();
  const auto& patches = tree_->patches.triangles;
  buffer_.insert(buffer_.end(), patches.begin() + tree_->patches.group_first[group],
                 patches.begin() + tree_->patches.group_first[group + 1]);
  place(std::int32_t(tree_->size() + group), end);
}

void LodCursor::place(std::int32_t id, std::size_t first) {
  const std::size_t n = buffer_.size() - first;
  block_first_[std::size_t(id)] = first;
  block_count_[std::size_t(id)] = std::int32_t(n);
  slot_owner_.resize(buffer_.size(), kInside);
  if (n) slot_owner_[first] = id;
}

void LodCursor::remove(std::int32_t id) {
  const std::size_t n = std::size_t(block_count_[std::size_t(id)]);
  if (n == 0) return;
  const std::size_t first = block_first_[std::size_t(id)];
  block_count_[std::size_t(id)] = 0;
  for (std::size_t i = first; i < first + n; ++i) {
    const std::int32_t v = buffer_[i][0];
    buffer_[i] = {v, v, v};  // zero area: drawn as nothing
    slot_owner_[i] = kHole;
  }
  holes_ += n;
  // Holes at the end are dropped: a move back down removes what the move up
  // appended last, so a slider going to and fro leaves few holes.
  while (!slot_owner_.empty() && slot_owner_.back() == kHole) {
    slot_owner_.pop_back();
    buffer_.pop_back();
    --holes_;
  }
}

void LodCursor::compact() {
  std::size_t write = 0;
  for (std::size_t read = 0; read < buffer_.size(); ++read) {
    const std::int32_t owner = slot_owner_[read];
    if (owner == kHole) continue;
    if (owner >= 0) block_first_[std::size_t(owner)] = write;
    buffer_[write] = buffer_[read];
    slot_owner_[write] = owner;
    ++write;
  }
  buffer_.resize(write);
  slot_owner_.resize(write);
  holes_ = 0;
}

}  // namespace scan2lod
