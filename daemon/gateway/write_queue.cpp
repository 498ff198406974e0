#include "gateway/write_queue.h"

#include <algorithm>

namespace drivegate {

WriteRequest& WriteQueue::push(std::unique_ptr<WriteRequest> r, TimePoint now) {
  r->state_ = WriteRequest::State::queued;
  r->deadline = now + write_timeout_;
  requests_.push_back(std::move(r));
  return *requests_.back();
}

bool WriteQueue::handed(WriteRequest& r, Ticket t, TimePoint now) {
  if (r.state_ == WriteRequest::State::carried) return false;
  r.state_ = WriteRequest::State::carried;
  r.ticket_ = t;
  // Each part gets the driver's whole write_timeout from when it is applied: the driver's own
  // deadline (shorter) fails it first, so a part the client was told failed is never still on
  // its way to the drive.
  r.deadline = now + write_timeout_;
  const Handed now_held = r.urgent ? Handed::stop : Handed::part;
  if (handed_ == Handed::nothing) {
    handed_ = now_held;
  } else if (handed_ != now_held) {
    handed_ = Handed::part_and_stop;
  }
  return true;
}

bool WriteQueue::confirmed(WriteRequest& r, TimePoint now) {
  if (r.state_ != WriteRequest::State::carried) return false;
  r.state_ = WriteRequest::State::between;
  r.deadline = now + write_timeout_;
  return true;
}

std::unique_ptr<WriteRequest> WriteQueue::remove(const WriteRequest* r) {
  const auto it = std::find_if(requests_.begin(), requests_.end(),
                               [r](const auto& owned) { return owned.get() == r; });
  if (it == requests_.end()) return nullptr;
  std::unique_ptr<WriteRequest> owned = std::move(*it);
  requests_.erase(it);
  return owned;
}

std::vector<std::unique_ptr<WriteRequest>> WriteQueue::take_all() {
  auto all = std::move(requests_);
  requests_.clear();
  if (handed_ == Handed::stop) handed_ = Handed::nothing;
  if (handed_ == Handed::part_and_stop) handed_ = Handed::part;
  return all;
}

WriteRequest* WriteQueue::carrying(Ticket t) const {
  const auto it = std::find_if(requests_.begin(), requests_.end(),
                               [t](const auto& r) { return r->carried() == t; });
  return it != requests_.end() ? it->get() : nullptr;
}

WriteRequest* WriteQueue::head() const {
  const auto it =
      std::find_if(requests_.begin(), requests_.end(), [](const auto& r) { return !r->urgent; });
  return it != requests_.end() ? it->get() : nullptr;
}

WriteRequest* WriteQueue::last_queued() const {
  const auto it =
      std::find_if(requests_.rbegin(), requests_.rend(), [](const auto& r) { return !r->urgent; });
  return it != requests_.rend() && !(*it)->started() ? it->get() : nullptr;
}

bool WriteQueue::full(bool urgent, bool reads_only) const {
  const auto n = std::count_if(requests_.begin(), requests_.end(), [&](const auto& r) {
    return r->urgent == urgent && r->reads_only == reads_only;
  });
  return static_cast<std::size_t>(n) >= kMaxQueuedWrites;
}

void WriteQueue::exchanged() {
  last_ = handed_ != Handed::nothing ? LastExchange::wrote : LastExchange::polled;
  handed_ = Handed::nothing;
}

PendingWrites WriteQueue::pending(bool driver_due) const {
  if (handed_ == Handed::stop || handed_ == Handed::part_and_stop) return PendingWrites::urgent;
  bool carried = false;
  for (const auto& r : requests_) {
    if (!r->carried() || !driver_due) continue;
    if (r->urgent) return PendingWrites::urgent;
    carried = true;
  }
  if (handed_ == Handed::part || carried) return PendingWrites::waiting;
  const WriteRequest* first = head();
  return first != nullptr && !first->carried() ? PendingWrites::waiting : PendingWrites::none;
}

}  // namespace drivegate
