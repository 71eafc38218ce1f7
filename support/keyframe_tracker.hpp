#pragma once
/// \file
/// KeyframeTracker: frame loss and keyframes of an image sequence (paper Sec. 4, eq. 22; docs/algorithm.md §7),
/// measured with two-view geometry only: each frame's features are matched to the last keyframe's
/// and verified by homography-versus-fundamental model selection (docs/algorithm.md §5). No map, no bundle
/// adjustment: this is the front end's view of "tracking", the part the features decide.
///
/// Per frame, in order:
/// 1. Frame to keyframe: match_features(keyframe, frame), select_model() on the matches; the
///    inliers are those of the chosen model. The frame is *tracked* when a model was chosen and it
///    has at least KeyframeTrackerOptions::min_inliers inliers, *lost* otherwise.
/// 2. A tracked frame becomes the new keyframe when its inliers are fewer than
///    KeyframeTrackerOptions::keyframe_inlier_ratio times the keyframe's feature count.
/// 3. After a lost frame the keyframe is kept: the next frame is matched against it again
///    (tracking recovers as soon as a frame matches it). When max_lost_frames consecutive frames
///    are lost, the keyframe is stale: the last of them becomes the keyframe (it stays counted as
///    lost; TrackedFrame::initialised is set) and tracking restarts from it.
/// 4. With no keyframe (the first frame, after reset()) the frame becomes the keyframe without
///    being tracked (initialised, not lost), provided it has at least min_inliers features (a
///    keyframe with fewer could never track a frame); otherwise it is lost.
/// 5. Frame to previous frame (only with a camera): match_features(previous, frame),
///    select_model(), relative_pose(): the relative rotation X_frame = R X_previous + t. When the
///    previous frame is the keyframe of step 1, its matches and model are reused.
///
/// Frame loss rate (paper eq. 22) = lost frames / frames; the first frame counts as a frame.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/geometry/relative_pose.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "affine_orb/matching/matcher.hpp"

namespace affine_orb {

/// Thresholds of KeyframeTracker.
struct KeyframeTrackerOptions {
  /// A frame is lost when fewer of its matches to the last keyframe than this are inliers of the
  /// chosen model. 30: ORB-SLAM2 declares tracking lost when fewer than 30 matched map points
  /// remain inliers after tracking the local map (Mur-Artal & Tardós, ORB-SLAM2, IEEE T-RO 2017;
  /// Tracking::TrackLocalMap). In [8, 1000000]: at least the sample size of select_model().
  int min_inliers = 30;
  /// A tracked frame becomes the new keyframe when its inliers fall below this share of the
  /// keyframe's features. 0.1: at 1000 features (ORB-SLAM2's TUM setting) a keyframe is taken
  /// before fewer than 100 of its features are verified, the match count ORB-SLAM2 requires of a
  /// new two-view reconstruction (Tracking::MonocularInitialization). Measured with
  /// examples/affine_orb_sequence on KITTI 06 (1000 plain features, default model selection): a frame
  /// shares 17–21 % of the features as inliers with the frame before, 11–13 % two frames apart and
  /// 7–10 % three apart, so at 10 Hz a keyframe is taken every 2–3 frames. In (0, 1].
  double keyframe_inlier_ratio = 0.1;
  /// Consecutive lost frames after which the keyframe is stale and the current frame replaces it.
  /// 3: a transient failure (one blurred, occluded or noisy frame) is recovered from by the
  /// frames after it; three failures in a row mean the camera has moved past the keyframe (on
  /// KITTI 06 with 1000 plain features, frames 5 to 9 frames past their keyframe fall below 30
  /// inliers, and later ones do not come back). >= 1.
  int max_lost_frames = 3;
  /// Model selection of frame-to-keyframe and frame-to-previous-frame matches.
  ModelSelectionOptions model_selection;
  /// Matching of two frames' features (docs/algorithm.md §4).
  AffineMatchOptions matching;
  /// Relative pose recovery (frame to previous frame, with a camera).
  RelativePoseOptions pose;

  /// Throws std::invalid_argument for values outside the ranges above or invalid nested options.
  void check() const {
    detail::require_range(min_inliers, {8, 1000000}, "KeyframeTrackerOptions::min_inliers");
    detail::require_range(keyframe_inlier_ratio, {0, 1, true}, "KeyframeTrackerOptions::keyframe_inlier_ratio");
    detail::require_range(max_lost_frames, detail::kPositive, "KeyframeTrackerOptions::max_lost_frames");
    model_selection.check();
    matching.check();
    pose.check();
  }
};

/// What KeyframeTracker::track() found for one frame.
struct TrackedFrame {
  /// Position of the frame in the sequence given to track() (0 = the first).
  int index = 0;
  /// Features of the frame.
  int features = 0;
  /// Index of the keyframe the frame was matched against; -1 when there was none.
  int reference_keyframe = -1;
  /// Matches to that keyframe (Match::query indexes the keyframe's features, Match::train this
  /// frame's), and which of them are inliers of the chosen model (one entry per match).
  std::vector<Match> matches;
  std::vector<std::uint8_t> inlier_mask;
  /// Inliers of the chosen model among `matches`.
  int inliers = 0;
  /// The model select_model() chose (kNone: fewer than 8 matches, degenerate, or no keyframe).
  GeometricModel model = GeometricModel::kNone;
  /// R_H of select_model() (paper eq. 22, docs/algorithm.md §5).
  double homography_ratio = 0.0;
  /// inliers / (features of the reference keyframe); 0 without a keyframe.
  double inlier_ratio = 0.0;
  /// Not tracked (see KeyframeTracker). Counted in the frame loss rate.
  bool lost = false;
  /// The frame became the keyframe.
  bool keyframe = false;
  /// The frame became the keyframe without being tracked: the first frame, or the last of
  /// max_lost_frames lost frames.
  bool initialised = false;

  /// Frame to previous frame (only with a camera; zero / kNone otherwise): matches, inliers of the
  /// chosen model, the model, and the relative pose X_frame = R X_previous + t.
  int previous_matches = 0;
  int previous_inliers = 0;
  GeometricModel previous_model = GeometricModel::kNone;
  RelativePose relative_pose;
};

/// Counts lost frames and keyframes of a sequence of feature sets (see the file comment for the
/// rules). `Bits` is the descriptor width of the Features (256 for Rbrief, 512 for Brisk).
///
/// Not thread-safe: one instance per sequence. The tracker keeps copies of the keyframe's and the
/// previous frame's features.
template <int Bits>
class KeyframeTracker {
 public:
  /// `camera`: intrinsics for the frame-to-previous relative pose; without one, step 5 is skipped.
  explicit KeyframeTracker(KeyframeTrackerOptions options = {}, std::optional<PinholeCamera> camera = std::nullopt)
      : options_((options.check(), std::move(options))), camera_(std::move(camera)) {
    if (camera_) camera_->check();
  }

  const KeyframeTrackerOptions& options() const { return options_; }
  const std::optional<PinholeCamera>& camera() const { return camera_; }

  /// Processes the next frame's features (from Extractor<...>::extract()).
  ///
  /// Throws std::invalid_argument when the keypoint, descriptor and view counts of `frame` are
  /// inconsistent (see match_features()). An empty frame is lost.
  TrackedFrame track(Features<Bits> frame) {
    detail::require(frame.descriptors.size() == frame.keypoints.size() &&
                        (frame.views.empty() || frame.views.size() == frame.keypoints.size()),
                    "KeyframeTracker::track: keypoints, descriptors and views differ in number");
    TrackedFrame out;
    out.index = frames_;
    out.features = static_cast<int>(frame.size());
    const bool can_be_keyframe = out.features >= options_.min_inliers;

    KeyframeMatch to_keyframe;
    if (keyframe_index_ < 0) {
      out.lost = !can_be_keyframe;
      out.keyframe = out.initialised = can_be_keyframe;
    } else {
      to_keyframe = match_keyframe(frame, out);
      if (!out.lost) {
        lost_streak_ = 0;
        out.keyframe = out.inlier_ratio < options_.keyframe_inlier_ratio;
      } else if (++lost_streak_ >= options_.max_lost_frames && can_be_keyframe) {
        out.keyframe = out.initialised = true;
      }
    }
    if (camera_ && has_previous_) relate_to_previous(frame, to_keyframe, out);
    count_and_keep(std::move(frame), out);
    return out;
  }

  /// Forgets the keyframe, the previous frame and the counts: the next frame starts a sequence.
  void reset() {
    keyframe_ = {};
    previous_ = {};
    has_previous_ = false;
    keyframe_index_ = -1;
    lost_streak_ = frames_ = lost_frames_ = keyframes_ = 0;
  }

  /// Frames processed, lost frames and keyframes taken (initialised ones included) since the start
  /// or the last reset().
  int frames() const { return frames_; }
  int lost_frames() const { return lost_frames_; }
  int keyframes() const { return keyframes_; }
  /// Frame loss rate, paper eq. 22: lost / frames (0 before the first frame).
  double frame_loss_rate() const {
    return frames_ == 0 ? 0.0 : static_cast<double>(lost_frames_) / static_cast<double>(frames_);
  }
  /// Index of the current keyframe (-1: none yet) and its features.
  int keyframe_index() const { return keyframe_index_; }
  const Features<Bits>& keyframe() const { return keyframe_; }

 private:
  /// select_model() on the matched points; an unsuccessful result for fewer than 8 matches.
  ModelSelectionResult select(const MatchedPoints& pairs) const {
    return select_model(pairs.points1, pairs.points2, options_.model_selection);
  }

  /// The model chosen between the keyframe and a frame, and the matched points it was chosen on
  /// (the relative pose needs both).
  struct KeyframeMatch {
    ModelSelectionResult selection;
    MatchedPoints pairs;
  };

  /// Matches `frame` to the keyframe and selects a model: fills out's reference keyframe, matches,
  /// model, homography ratio, inliers and inlier ratio, and `lost` (no model or fewer than
  /// min_inliers inliers). Returns the selection and its points.
  KeyframeMatch match_keyframe(const Features<Bits>& frame, TrackedFrame& out) const {
    KeyframeMatch match;
    out.reference_keyframe = keyframe_index_;
    out.matches = match_features(keyframe_, frame, options_.matching);
    matched_points(keyframe_.keypoints, frame.keypoints, out.matches, match.pairs);
    match.selection = select(match.pairs);
    out.model = match.selection.model;
    out.homography_ratio = match.selection.homography_ratio;
    out.inlier_mask = match.selection.chosen_inliers();
    out.inliers = match.selection.chosen_inlier_count();
    out.inlier_ratio =
        keyframe_.empty() ? 0.0 : static_cast<double>(out.inliers) / static_cast<double>(keyframe_.size());
    out.lost = !match.selection.success || out.inliers < options_.min_inliers;
    return match;
  }

  /// Step 5, frame to previous frame: fills out's previous matches, inliers, model and relative
  /// pose. When the previous frame is the keyframe `to_keyframe` (its match) is reused.
  void relate_to_previous(const Features<Bits>& frame, const KeyframeMatch& to_keyframe, TrackedFrame& out) const {
    if (out.reference_keyframe >= 0 && out.reference_keyframe == frames_ - 1) {
      out.previous_matches = static_cast<int>(out.matches.size());
      out.previous_inliers = out.inliers;
      out.previous_model = out.model;
      out.relative_pose = relative_pose(to_keyframe.selection, *camera_, to_keyframe.pairs.points1,
                                        to_keyframe.pairs.points2, options_.pose);
      return;
    }
    const std::vector<Match> matches = match_features(previous_, frame, options_.matching);
    const MatchedPoints pairs = matched_points(previous_.keypoints, frame.keypoints, matches);
    const ModelSelectionResult selection = select(pairs);
    out.previous_matches = static_cast<int>(matches.size());
    out.previous_inliers = selection.chosen_inlier_count();
    out.previous_model = selection.model;
    out.relative_pose = relative_pose(selection, *camera_, pairs.points1, pairs.points2, options_.pose);
  }

  /// Counts the tracked frame `out` and keeps `frame` as the keyframe when it became one, and as
  /// the previous frame when there is a camera.
  void count_and_keep(Features<Bits> frame, const TrackedFrame& out) {
    ++frames_;
    lost_frames_ += out.lost ? 1 : 0;
    if (out.keyframe) {
      ++keyframes_;
      keyframe_ = frame;
      keyframe_index_ = out.index;
      lost_streak_ = 0;
    }
    if (camera_) {
      previous_ = std::move(frame);
      has_previous_ = true;
    }
  }

  KeyframeTrackerOptions options_;
  std::optional<PinholeCamera> camera_;
  Features<Bits> keyframe_;
  Features<Bits> previous_;
  bool has_previous_ = false;
  int keyframe_index_ = -1;
  int lost_streak_ = 0;
  int frames_ = 0;
  int lost_frames_ = 0;
  int keyframes_ = 0;
};

}  // namespace affine_orb
