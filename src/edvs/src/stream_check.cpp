#include "edvs/stream_check.h"

#include <algorithm>

namespace edvs {

namespace {
bool samePixel(const ebslam::Event& a, const ebslam::Event& b) {
  return a.x == b.x && a.y == b.y && a.polarity == b.polarity;
}
}  // namespace

StreamComparison compareStreams(const ebslam::EventVector& sent, const ebslam::EventVector& decoded,
                                bool compare_times, std::int64_t period_us, std::size_t window) {
  StreamComparison c;
  c.sent = sent.size();
  c.published = decoded.size();
  if (sent.empty()) {
    c.invented = decoded.size();
    return c;
  }
  std::uint16_t min_x = sent.front().x, max_x = min_x, min_y = sent.front().y, max_y = min_y;
  for (const ebslam::Event& e : sent) {
    min_x = std::min(min_x, e.x);
    max_x = std::max(max_x, e.x);
    min_y = std::min(min_y, e.y);
    max_y = std::max(max_y, e.y);
  }
  // Offset of the decoded clock: the first decoded event that agrees with an early true event.
  bool have_offset = !compare_times;
  for (std::size_t k = 0; k < decoded.size() && !have_offset && k < window; ++k) {
    for (std::size_t j = 0; j < std::min(window, sent.size()); ++j) {
      if (!samePixel(decoded[k], sent[j])) continue;
      const std::int64_t d = decoded[k].t_us - sent[j].t_us;
      if (period_us > 0 ? (d % period_us) == 0 : true) {
        c.offset_us = d;
        have_offset = true;
        break;
      }
    }
  }
  std::size_t next = 0;  // next true event still to come
  for (std::size_t k = 0; k < decoded.size(); ++k) {
    const ebslam::Event& g = decoded[k];
    if (k > 0 && g.t_us < decoded[k - 1].t_us) ++c.backwards;
    const std::int64_t t = g.t_us - c.offset_us;
    std::size_t found = sent.size();
    for (std::size_t j = next; j < std::min(sent.size(), next + window); ++j) {
      if (samePixel(g, sent[j]) && (!compare_times || sent[j].t_us == t)) {
        found = j;
        break;
      }
      if (compare_times && sent[j].t_us > t) break;  // true times only grow
    }
    if (found < sent.size()) {
      c.lost += found - next;
      next = found + 1;
      ++c.matched;
      continue;
    }
    ++c.invented;
    if (g.x < min_x || g.x > max_x || g.y < min_y || g.y > max_y) ++c.invented_outside_pixels;
    if (compare_times) {
      const std::int64_t ahead = t - sent[std::min(next, sent.size() - 1)].t_us;
      c.max_ahead_us = std::max(c.max_ahead_us, ahead);
    }
  }
  c.lost += sent.size() - next;
  if (!decoded.empty()) c.final_error_us = decoded.back().t_us - c.offset_us - sent.back().t_us;
  return c;
}

}  // namespace edvs
