#include "simulator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "drivegate/sim_rx.h"
#include "drivegate/sim_text.h"

namespace drivegate::framed {
namespace {

constexpr Millis kFrameGap{50};  // a pause this long drops a partial frame
constexpr const char* kHelp = "state, set NAME VALUE, silent on|off, corrupt N, help";

std::optional<double> number(const std::string& s) {
  if (const auto u = parse_unsigned(s)) return static_cast<double>(*u);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0' || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

FramedSimulator::FramedSimulator(std::shared_ptr<const Description> d, const SimEnv& env)
    : d_(std::move(d)), codec_(*d_), state_(*d_, env.options, env.address) {
  sent_.assign(d_->field_names.size(), 0.0);
}

Bytes FramedSimulator::send(std::size_t message, std::span<const double> sent) {
  const Message& m = d_->messages[message];
  std::array<double, kMaxFields> values{};
  state_.fill(m, sent, values);
  // An echoed field (a mode, a sequence number) is the request's.
  for (const auto& [field, global] : m.echo) {
    if (global < sent.size()) values[field] = sent[global];
  }
  Bytes frame = codec_.encode(message, {values.data(), m.fields.size()});
  if (corrupt_ > 0 && !frame.empty()) {
    --corrupt_;
    frame.back() ^= 0xFF;
  }
  return frame;
}

Bytes FramedSimulator::answer(const Frame& request, TimePoint now) {
  (void)now;
  const Message& req = d_->messages[request.message];
  std::array<double, kMaxFields> values{};
  codec_.values(request, values);
  state_.lay_out(req, {values.data(), req.fields.size()}, sent_);
  const Scope s = state_.scope_with(sent_, sent_);
  std::optional<std::size_t> reply;
  bool ruled = false;
  for (const Simulated::Rule& r : d_->sim.rules) {
    if (r.request != request.message) continue;
    if (r.when && !r.when->holds(s)) continue;
    state_.assign(r.update, s);
    reply = r.reply;
    ruled = true;
    break;
  }
  if (!ruled || !reply) {
    if (!req.replies.empty()) reply = req.replies.front();
  }
  state_.derive();
  if (!reply) return {};
  return send(*reply, sent_);
}

Bytes FramedSimulator::on_receive(ByteView rx, TimePoint now) {
  if (silent_) return {};
  advance(now);
  if (!rx_.empty() && last_byte_ && now - *last_byte_ > kFrameGap) rx_.clear();
  if (!rx.empty()) last_byte_ = now;
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  const auto decode = [this](ByteView b) { return codec_.decode(Direction::request, b); };
  while (const auto d = take_decoded(rx_, decode)) {
    if (d->status == DecodeStatus::bad) {
      if (d->error == make_error_code(FrameError::bad_checksum) && d_->sim.nack) {
        ++rejected_;
        const Bytes nack = send(*d_->sim.nack, {});
        out.insert(out.end(), nack.begin(), nack.end());
      }
      continue;
    }
    ++frames_;
    const Bytes reply = answer(d->frame, now);
    out.insert(out.end(), reply.begin(), reply.end());
  }
  return out;
}

void FramedSimulator::advance(TimePoint now) {
  const double dt =
      last_tick_
          ? static_cast<double>(std::chrono::duration_cast<Millis>(now - *last_tick_).count())
          : 0.0;
  last_tick_ = now;
  state_.set(builtin::dt_ms, dt);
  state_.assign(d_->sim.tick, state_.scope());
  state_.derive();
}

Bytes FramedSimulator::on_tick(TimePoint now) {
  advance(now);
  if (d_->sim.stream.empty() || silent_) return {};
  if (!next_stream_) next_stream_ = now;
  if (now < *next_stream_) return {};
  const double every = std::clamp(d_->sim.stream_ms.num(state_.scope()), 10.0, 60'000.0);
  *next_stream_ = now + Millis(static_cast<std::int64_t>(every));
  for (const Simulated::Stream& s : d_->sim.stream) {
    if (!s.when || s.when->holds(state_.scope())) return send(s.send, {});
  }
  return {};
}

std::string FramedSimulator::state() const {
  std::ostringstream s;
  s << "protocol=" << d_->name;
  for (std::size_t i = builtin::count; i < d_->vars.size(); ++i) {
    const Var& v = d_->vars[i];
    if (v.kind == Var::Kind::option) continue;
    s << " " << v.name << "=";
    if (!state_.known(i)) {
      s << "?";
    } else if (state_.vars()[i].is_text()) {
      s << *state_.vars()[i].str;
    } else {
      s << state_.num(i);
    }
  }
  s << " silent=" << silent_ << " corrupt=" << corrupt_ << " frames=" << frames_
    << " rejected=" << rejected_;
  return s.str();
}

std::string FramedSimulator::control(std::string_view text, TimePoint now) {
  advance(now);
  const ControlLine line(text, kHelp);
  if (auto answer = line.common()) return *answer;
  const std::vector<std::string>& w = line.words();
  if (w[0] == "state" && w.size() == 1) return state();
  if (w[0] == "silent" && w.size() == 2 && parse_on_off(w[1])) {
    silent_ = *parse_on_off(w[1]);
    rx_.clear();
    return std::string("ok silent=") + (silent_ ? "1" : "0");
  }
  if (w[0] == "corrupt" && w.size() == 2) {
    if (const auto n = parse_unsigned(w[1], 1000)) {
      corrupt_ = static_cast<int>(*n);
      return "ok corrupt=" + std::to_string(corrupt_);
    }
  }
  if (w[0] == "set" && w.size() == 3) {
    const auto v = d_->var(w[1]);
    const auto x = number(w[2]);
    if (!v || (d_->vars[*v].kind != Var::Kind::point && d_->vars[*v].kind != Var::Kind::state)) {
      return line.error("no point or state '" + w[1] + "'");
    }
    if (!x) return line.error("'" + w[2] + "' is not a number");
    state_.set(*v, *x);
    state_.derive();
    return "ok " + w[1] + "=" + w[2];
  }
  return line.unknown();
}

}  // namespace drivegate::framed
