// A shipped description and its codec, for the framed adapter's tests: messages and fields by
// name, frames by hex.
#pragma once

#include <gtest/gtest.h>

#include <initializer_list>
#include <memory>
#include <string>
#include <utility>

#include "codec.h"
#include "description.h"
#include "settings.h"

namespace drivegate::framed::test {

using Fields = std::initializer_list<std::pair<const char*, double>>;

inline std::shared_ptr<const Description> shipped(const std::string& name) {
  std::string error;
  auto d = load_description(name, error);
  EXPECT_NE(d, nullptr) << error;
  return d;
}

// "A5 05 00" -> bytes.
inline Bytes hex(const std::string& s) {
  Bytes out;
  std::size_t i = 0;
  while (i < s.size()) {
    if (s[i] == ' ') {
      ++i;
      continue;
    }
    out.push_back(static_cast<std::uint8_t>(std::stoul(s.substr(i, 2), nullptr, 16)));
    i += 2;
  }
  return out;
}

class Protocol {
 public:
  explicit Protocol(const std::string& name) : d_(shipped(name)), codec_(*d_) {}

  [[nodiscard]] std::size_t message(const std::string& name) const {
    const auto m = d_->message(name);
    EXPECT_TRUE(m.has_value()) << "no message " << name;
    return m.value_or(0);
  }
  // The message's bytes with these field values (the others 0).
  [[nodiscard]] Bytes encode(const std::string& name, Fields fields = {}) const {
    const std::size_t m = message(name);
    std::array<double, kMaxFields> v{};
    for (const auto& [field, value] : fields) v.at(field_index(m, field)) = value;
    return codec_.encode(m, {v.data(), d_->messages[m].fields.size()});
  }
  [[nodiscard]] std::size_t field_index(std::size_t m, const std::string& field) const {
    const auto& f = d_->messages[m].fields;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f[i].name == field) return i;
    }
    ADD_FAILURE() << "no field " << field << " in " << d_->messages[m].name;
    return 0;
  }
  // A frame is read in place: the fixture keeps the bytes of the last one decoded.
  [[nodiscard]] Decoded<Frame> decode(Direction dir, const Bytes& rx) const {
    last_ = rx;
    return codec_.decode(dir, last_);
  }
  [[nodiscard]] std::string name_of(const Decoded<Frame>& d) const {
    return d.status == DecodeStatus::frame ? d_->messages[d.frame.message].name : "";
  }
  [[nodiscard]] double field(const Decoded<Frame>& d, const std::string& name) const {
    return codec_.value(d.frame, field_index(d.frame.message, name));
  }
  [[nodiscard]] const Description& description() const { return *d_; }
  [[nodiscard]] const Codec& codec() const { return codec_; }

 private:
  std::shared_ptr<const Description> d_;
  Codec codec_;
  mutable Bytes last_;
};

}  // namespace drivegate::framed::test
