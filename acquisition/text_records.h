// Text bodies of one record a line (.xyz/.pts, ASCII PLY vertices, ASCII
// PCD), parsed on all cores: the text is cut at line ends into blocks, a
// first pass counts each block's records, and a second parses the blocks at
// once, each record written to its own index. Published archives are ASCII,
// and users do not convert them first (issue 32: read at the disk's speed).
//
// Errors come out as reading the lines in order would give them: the first
// bad line's.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

namespace scan2lod {

// The whole file from byte `offset` on, read in one piece (no per-character
// stream iterators). Throws InputError when it cannot be opened.
std::string read_file_from(const std::string& path, std::size_t offset = 0);

struct TextBlock {
  std::string_view text;      // whole lines, the last one's end included
  std::size_t first_line = 0;   // the number of its first line
  std::size_t first_record = 0; // the index of its first record
  std::size_t records = 0;
};

// Splits [at, end) into the next line, without its '\n' and a '\r' before it.
inline std::string_view next_line(const char*& at, const char* end) {
  const char* stop = static_cast<const char*>(std::memchr(at, '\n', std::size_t(end - at)));
  if (!stop) stop = end;
  std::string_view line(at, std::size_t(stop - at));
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  at = stop < end ? stop + 1 : end;
  return line;
}

// Cuts `text` (whose first line is number `first_line`) into blocks at line
// ends and counts the lines `is_record` takes, up to `max_records` of them:
// the text after the last one taken is left out. Small texts are one block.
template <class IsRecord>
std::vector<TextBlock> cut_records(std::string_view text, std::size_t first_line, std::size_t max_records,
                                   const IsRecord& is_record) {
  // Blocks of 1 MB: a few per core on a file worth splitting, one below that.
  const std::size_t block_bytes = std::size_t(1) << 20;
  std::vector<TextBlock> blocks;
  for (std::size_t at = 0; at < text.size();) {
    std::size_t stop = std::min(text.size(), at + block_bytes);
    if (stop < text.size()) {
      const std::size_t eol = text.find('\n', stop - 1);
      stop = eol == std::string_view::npos ? text.size() : eol + 1;
    }
    blocks.push_back({text.substr(at, stop - at), 0, 0, 0});
    at = stop;
  }
  std::vector<std::size_t> lines(blocks.size(), 0);
  // Counting is a tenth of parsing, but for large files still worth both cores.
#pragma omp parallel for schedule(dynamic, 1) if (blocks.size() > 2)
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const char* at = blocks[b].text.data();
    const char* const end = at + blocks[b].text.size();
    while (at < end) {
      blocks[b].records += is_record(next_line(at, end)) ? 1 : 0;
      ++lines[b];
    }
  }
  std::size_t line = first_line, record = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    blocks[b].first_line = line;
    blocks[b].first_record = record;
    if (record + blocks[b].records >= max_records) {
      // The last block ends with the last record taken.
      const char* at = blocks[b].text.data();
      const char* const end = at + blocks[b].text.size();
      std::size_t taken = 0;
      while (at < end && record + taken < max_records) taken += is_record(next_line(at, end)) ? 1 : 0;
      blocks[b].text = blocks[b].text.substr(0, std::size_t(at - blocks[b].text.data()));
      blocks[b].records = taken;
      blocks.resize(b + 1);
      break;
    }
    line += lines[b];
    record += blocks[b].records;
  }
  return blocks;
}

// The records of the blocks together.
inline std::size_t record_count(const std::vector<TextBlock>& blocks) {
  return blocks.empty() ? 0 : blocks.back().first_record + blocks.back().records;
}

// Calls parse(line, line_number, record) for each record line of the blocks,
// blocks in parallel; rethrows the first block's exception, if any.
template <class IsRecord, class Parse>
void parse_records(const std::vector<TextBlock>& blocks, const IsRecord& is_record, const Parse& parse) {
  std::vector<std::exception_ptr> failures(blocks.size());
#pragma omp parallel for schedule(dynamic, 1) if (blocks.size() > 2)
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    try {
      const char* at = blocks[b].text.data();
      const char* const end = at + blocks[b].text.size();
      std::size_t line = blocks[b].first_line, record = blocks[b].first_record;
      for (; at < end; ++line) {
        const std::string_view text = next_line(at, end);
        if (is_record(text)) parse(text, line, record++);
      }
    } catch (...) {
      failures[b] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

}  // namespace scan2lod
