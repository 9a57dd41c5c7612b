// Sizes as users write them on the command line: 400M, 4G, 1.5GiB, 123456.
#pragma once

#include <string>

namespace scan2lod::cli {

// Bytes for a number with an optional unit K, M, G or T (powers of 1024; a
// trailing "B" or "iB" is allowed). Returns 0 for anything else.
double parse_bytes(const std::string& text);

// For CLI11's check(): empty when `text` is a size, else what was expected.
std::string size_problem(const std::string& text);

}  // namespace scan2lod::cli
