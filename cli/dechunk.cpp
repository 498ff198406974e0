#include "dechunk.h"

namespace drivegate::cli {

namespace {
constexpr std::size_t kMaxLine = 4096;

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

bool Dechunker::feed(std::string_view in, std::string& out) {
  std::size_t i = 0;
  while (i < in.size()) {
    switch (state_) {
      case State::size:
      case State::data_crlf:
      case State::trailer: {
        const char c = in[i++];
        if (c != '\n') {
          line_.push_back(c);
          if (line_.size() > kMaxLine) state_ = State::error;
          break;
        }
        if (!line_.empty() && line_.back() == '\r') line_.pop_back();
        const std::string line = std::move(line_);
        line_.clear();
        if (state_ == State::data_crlf) {
          if (!line.empty())
            state_ = State::error;
          else
            state_ = State::size;
        } else if (state_ == State::trailer) {
          if (line.empty()) state_ = State::done;
        } else {
          std::size_t size = 0;
          std::size_t k = 0;
          for (; k < line.size() && hex_value(line[k]) >= 0; ++k) {
            if (size > (SIZE_MAX >> 4)) {
              state_ = State::error;
              return false;
            }
            size = size * 16 + static_cast<std::size_t>(hex_value(line[k]));
          }
          if (k == 0) {
            state_ = State::error;
            break;
          }
          left_ = size;
          state_ = size == 0 ? State::trailer : State::data;
        }
        break;
      }
      case State::data: {
        const std::size_t n = std::min(left_, in.size() - i);
        out.append(in.substr(i, n));
        i += n;
        left_ -= n;
        if (left_ == 0) state_ = State::data_crlf;
        break;
      }
      case State::done:
        return true;  // anything after the body is ignored
      case State::error:
        return false;
    }
  }
  return state_ != State::error;
}

}  // namespace drivegate::cli
