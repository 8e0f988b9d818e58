// t-DASP video segmentation (thesis ch. 5): temporal-stable superpixels (streaming DASP), their
// strands and the reduced strand graph, spectral globalisation of the strand graph (eq. 5.16)
// and Semi-Supervised Hysteresis Segmentation, giving per frame a segment label image whose
// labels persist from frame to frame. Memory and time per frame are bounded by
// StrandConfig::max_strands on an endless stream.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/hysteresis_segmentation.h"
#include "dasp/spectral.h"
#include "dasp/strands.h"
#include "dasp/streaming_dasp.h"

namespace dasp {

/// Parameters of t-DASP.
struct TdaspConfig {
  StreamingDaspConfig superpixels;
  StrandConfig strands;
  SpectralConfig spectral;  ///< globalisation of the strand graph (kMax normalisation expected)
  HysteresisConfig hysteresis;
};

/// Wall-clock time of the stages of one frame, milliseconds.
struct TdaspTimings {
  double superpixels_ms = 0.0;  ///< streaming DASP
  double graph_ms = 0.0;        ///< superpixel graph and strand update
  double spectral_ms = 0.0;     ///< globalisation of the strand graph
  double labelling_ms = 0.0;    ///< hysteresis segmentation and label image
  double total_ms = 0.0;
};

/// Result of one frame.
struct TdaspFrame {
  StreamingDaspFrame superpixels;
  std::vector<std::int64_t> strand_id;      ///< per superpixel
  std::vector<std::int64_t> segment_label;  ///< per superpixel
  /// Segment label per pixel, CV_32SC1, -1 where no superpixel is. Labels < 2^31 (throws
  /// std::overflow_error when a stream creates more segment labels than that).
  cv::Mat segment_labels;
  int strand_count = 0;       ///< nodes of the reduced strand graph
  int strand_edge_count = 0;  ///< its edges
  HysteresisResult labelling;
  TdaspTimings timings;
};

/// t-DASP over a stream of RGB-D frames.
class TemporalDasp {
 public:
  explicit TemporalDasp(const TdaspConfig& config = {});
  TdaspFrame process(const RgbdFrame& frame);
  const StrandGraph& strandGraph() const { return strands_; }
  const TdaspConfig& config() const { return config_; }

 private:
  TdaspConfig config_;
  StreamingDasp superpixels_;
  StrandGraph strands_;
  std::int64_t next_label_ = 0;
};

}  // namespace dasp
