// Reading a gzip-compressed text file (a run's replay.jsonl.gz) line by line.
#pragma once

#include <zlib.h>

#include <string>

namespace fleet::ctl {

/// The next line of `f` (with its '\n', if it has one) into `line`; false at the end.
bool readGzLine(gzFile f, std::string& line);

}  // namespace fleet::ctl
