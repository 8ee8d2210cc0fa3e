#include "gzip_bytes.h"

#include <zlib.h>

namespace at {

namespace {

struct DeflateStream {
  z_stream zs{};
  bool ready = false;
  DeflateStream() { ready = deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) == Z_OK; }
  ~DeflateStream() {
    if (ready) deflateEnd(&zs);
  }
  DeflateStream(const DeflateStream&) = delete;
  DeflateStream& operator=(const DeflateStream&) = delete;
};

}  // namespace

Result<std::string> gzipBytes(const std::string& path, const std::string& plain) {
  DeflateStream stream;
  if (!stream.ready) return fail(path + ": zlib could not start compressing");
  z_stream& zs = stream.zs;
  std::string out;
  out.resize(deflateBound(&zs, uLong(plain.size())) + 64);
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(plain.data()));
  zs.avail_in = uInt(plain.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = uInt(out.size());
  if (deflate(&zs, Z_FINISH) != Z_STREAM_END) return fail(path + ": zlib could not compress the data");
  out.resize(zs.total_out);
  return out;
}

}  // namespace at
