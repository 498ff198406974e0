// HTTP/1.1 chunked transfer coding, decoded incrementally (RFC 9112, 7.1): bytes in as they come
// from the socket, the body out. Pure: no I/O. Chunk extensions and trailers are skipped.
#pragma once

#include <string>
#include <string_view>

namespace drivegate::cli {

class Dechunker {
 public:
  // Decodes `in`, appending body bytes to `out`. False on a malformed coding (then stuck).
  bool feed(std::string_view in, std::string& out);
  // The last (zero-size) chunk and its trailers have been read.
  [[nodiscard]] bool done() const { return state_ == State::done; }

 private:
  enum class State { size, data, data_crlf, trailer, done, error };
  State state_ = State::size;
  std::string line_;      // the size line or trailer line being read
  std::size_t left_ = 0;  // of the current chunk's data
};

}  // namespace drivegate::cli
