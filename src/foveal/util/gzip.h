// foveal/util/gzip.h — gzip files (zlib), read bounded and written whole or not at all.
#pragma once

#include <string>

namespace foveal {

// The decompressed content of a gzip file (a plain file is read as it is); throws Error naming
// the file when it cannot be read, is corrupt, or inflates past `max_bytes`.
std::string read_gzip_file(const std::string& path, size_t max_bytes = size_t(1) << 30);

// Write `bytes` to `path` — gzip-compressed (deterministic: no name, no time in the header) where
// `compress`, else as they are — through a temporary file beside it renamed into place, so that a
// failed write leaves nothing. Refuses to write over an input (util/files.h).
void write_file_atomically(const std::string& path, const std::string& bytes, bool compress);

}  // namespace foveal
