// foveal/util/gzip.cpp — gzip through zlib.
#include "foveal/util/gzip.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace foveal {

std::string read_gzip_file(const std::string& path, size_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail("{}: is a folder, not a file", path);
  if (!std::filesystem::exists(path, ec)) fail("{}: no such file", path);
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) fail("{}: cannot open file", path);
  note_input(path);
  std::string out;
  std::vector<char> chunk(1 << 16);
  for (;;) {
    const int got = gzread(f, chunk.data(), static_cast<unsigned>(chunk.size()));
    if (got < 0) {
      int code = 0;
      const std::string why = gzerror(f, &code);
      gzclose(f);
      fail("{}: not a readable gzip file ({})", path, why);
    }
    if (got == 0) break;
    if (out.size() + static_cast<size_t>(got) > max_bytes) {
      gzclose(f);
      fail("{}: more than {} MiB uncompressed; foveal reads inputs of up to {} MiB", path, max_bytes >> 20, max_bytes >> 20);
    }
    out.append(chunk.data(), static_cast<size_t>(got));
  }
  gzclose(f);
  return out;
}

void write_file_atomically(const std::string& path, const std::string& bytes, bool compress) {
  check_output_file(path);  // its folder exists, it is no folder, it may be written
  check_not_an_input(path);
  const std::filesystem::path target(path);
  const std::string temporary = partial_path(path);
  bool ok = false;
  if (compress) {
    // zlib's gzip stream: level 6, no file name, modification time 0 — the same bytes every run
    std::vector<unsigned char> out(compressBound(static_cast<uLong>(bytes.size())) + 64);
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) fail("{}: cannot compress", path);
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    z.avail_in = static_cast<uInt>(bytes.size());
    z.next_out = out.data();
    z.avail_out = static_cast<uInt>(out.size());
    const int status = deflate(&z, Z_FINISH);
    const size_t size = z.total_out;
    deflateEnd(&z);
    if (status != Z_STREAM_END) fail("{}: cannot compress", path);
    std::ofstream f(temporary, std::ios::binary);
    f.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(size));
    f.close();
    ok = static_cast<bool>(f);
  } else {
    std::ofstream f(temporary, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.close();
    ok = static_cast<bool>(f);
  }
  std::error_code ec;
  if (ok) std::filesystem::rename(temporary, target, ec);
  if (!ok || ec) {
    std::filesystem::remove(temporary, ec);
    fail("{}: cannot write", path);
  }
}

}  // namespace foveal
