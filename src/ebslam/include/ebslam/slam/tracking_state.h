#pragma once

// Whether a localisation filter believes it follows the sensor: one state for EB-SLAM-2D's
// TrackingMonitor (ebslam2d_tracking.h) and EB-SLAM-3D's health (ebslam3d.h), so that their users
// (the exploration, the ROS nodes' diagnostics) read both the same way. The two detectors differ
// (2D: map contrast at the estimate per control period; 3D: the particles' fit ratio per batch).

namespace ebslam {

enum class TrackingState {
  kTracking,    ///< the events agree with the map at the estimate
  kLost,        ///< they have not for a while: the estimate is not to be trusted
  kRecovering,  ///< the fit came back but not yet for long enough (EB-SLAM-3D only)
  /// hypotheses spread over the map, not yet converged (EB-PF's global localisation)
  kGlobalSearch,
};
/// "tracking", "lost", "recovering" or "global_search".
const char* toString(TrackingState state);

}  // namespace ebslam
