#include "fragg_map/lock_holders.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <utility>

namespace fragg {

HolderTicket& HolderTicket::operator=(HolderTicket&& other) noexcept {
  if (this != &other) {
    if (board_) board_->leave(id_);
    board_ = other.board_;
    id_ = other.id_;
    other.board_ = nullptr;
  }
  return *this;
}

HolderTicket::~HolderTicket() {
  if (board_) board_->leave(id_);
}

HolderTicket LockHolders::enter(const char* who, bool writes) {
  const Clock::time_point t = Clock::now();
  std::lock_guard<std::mutex> guard(mutex_);
  const uint64_t id = next_id_++;
  holding_.push_back({id, who, writes, t});
  return HolderTicket(this, id);
}

void LockHolders::leave(uint64_t id) {
  const Clock::time_point t = Clock::now();
  std::lock_guard<std::mutex> guard(mutex_);
  const auto it =
      std::find_if(holding_.begin(), holding_.end(), [id](const Entry& e) { return e.id == id; });
  if (it == holding_.end()) return;
  left_[departures_ % kKept] = {it->who, it->writes,
                                std::chrono::duration<double, std::milli>(t - it->since).count()};
  ++departures_;
  *it = holding_.back();
  holding_.pop_back();
}

LockHolders::Mark LockHolders::startWaiting() {
  std::lock_guard<std::mutex> guard(mutex_);
  ++waiting_;
  return {departures_};
}

size_t LockHolders::writersWaiting() const {
  std::lock_guard<std::mutex> guard(mutex_);
  return waiting_;
}

std::vector<LockHolder> LockHolders::doneWaiting(const Mark& mark) {
  std::lock_guard<std::mutex> guard(mutex_);
  --waiting_;
  const uint64_t first = std::max(mark.departures, departures_ > kKept ? departures_ - kKept : 0);
  std::vector<LockHolder> out;
  out.reserve(static_cast<size_t>(departures_ - std::min(first, departures_)));
  for (uint64_t d = first; d < departures_; ++d) out.push_back(left_[d % kKept]);
  return out;
}

std::vector<LockHolder> LockHolders::now() const {
  const Clock::time_point t = Clock::now();
  std::lock_guard<std::mutex> guard(mutex_);
  std::vector<LockHolder> out;
  out.reserve(holding_.size());
  for (const Entry& e : holding_)
    out.push_back(
        {e.who, e.writes, std::chrono::duration<double, std::milli>(t - e.since).count()});
  return out;
}

std::string describeLockHolders(const std::vector<LockHolder>& holders, size_t most) {
  struct Sum {
    const char* who;
    size_t count;
    double ms;
  };
  std::vector<Sum> sums;
  for (const LockHolder& h : holders) {
    auto it = std::find_if(sums.begin(), sums.end(),
                           [&](const Sum& s) { return std::strcmp(s.who, h.who) == 0; });
    if (it == sums.end())
      sums.push_back({h.who, 1, h.held_ms});
    else
      ++it->count, it->ms += h.held_ms;
  }
  std::stable_sort(sums.begin(), sums.end(),
                   [](const Sum& a, const Sum& b) { return a.ms > b.ms; });
  std::string out;
  for (size_t i = 0; i < sums.size() && i < most; ++i) {
    if (!out.empty()) out += "; ";
    std::string who = sums[i].who;
    std::replace(who.begin(), who.end(), ',', ' ');
    out += sums[i].count > 1 ? fmt::format("{} x{} {:.1f} ms", who, sums[i].count, sums[i].ms)
                             : fmt::format("{} {:.1f} ms", who, sums[i].ms);
  }
  if (sums.size() > most) out += fmt::format("; +{} more", sums.size() - most);
  return out;
}

}  // namespace fragg
