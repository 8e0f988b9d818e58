#include "ebslam/slam/tracking_state.h"

namespace ebslam {

const char* toString(TrackingState state) {
  switch (state) {
    case TrackingState::kTracking:
      return "tracking";
    case TrackingState::kLost:
      return "lost";
    case TrackingState::kRecovering:
      return "recovering";
    case TrackingState::kGlobalSearch:
      return "global_search";
  }
  return "unknown";
}

}  // namespace ebslam
