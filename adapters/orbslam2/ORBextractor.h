#pragma once
/// \file
/// Drop-in replacement of ORB-SLAM2's ORBextractor backed by affine_orb (docs/algorithm.md §6; adapters/README.md
/// says how to swap it in). Replace the fork's include/ORBextractor.h and src/ORBextractor.cc by
/// this file and ORBextractor.cc, add affine_orb's `include/` and `adapters/common/` directories to
/// the include path, rebuild; nothing else in the fork changes.
///
/// Guarantees (for every call with a non-empty CV_8UC1 image):
/// - keypoints: `pt` in level-0 pixels; `octave` in [0, nlevels), σ = s^octave (a keypoint of a view
///   of tilt t found on level l has scale s^l·√t and gets the nearest octave, clamped); `size` =
///   31·s^octave; `angle` in degrees, [0, 360); `response` the FAST score; grouped by octave, level
///   0 first;
/// - descriptors: N x 32 CV_8U (released when N = 0), row i for keypoint i. rBRIEF rows are
///   bit-compatible with ORB; with BRISK, the first 256 of its 512 bits;
/// - mvImagePyramid[l]: the image at level l, round(W/s^l) x round(H/s^l), a fresh copy each frame;
///   every keypoint lies 10 px (the 11x11 stereo window plus its ±5 px search) inside
///   mvImagePyramid[octave] at round(pt / s^octave);
/// - an empty image returns at once with every output untouched; another image type, or a mask that
///   is neither empty nor CV_8UC1 of the image size, throws std::invalid_argument. The mask is
///   honoured (non-zero = allowed).
/// Two instances share nothing but the guarded defaults of SetAffineOptions(), so they can run on
/// two threads at once (stereo); one instance must not be called from two threads at once.

#include <list>  // ORB-SLAM2's original header provides <list> and <vector> to the files including it
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb_adapter/options.hpp"

namespace ORB_SLAM2 {

/// The Affine-ORB options ORB-SLAM2's constructor cannot carry (affine_orb_adapter/options.hpp).
using AffineOrbAdapterOptions = affine_orb::adapters::AdapterOptions;

class ORBextractor {
 public:
  enum { HARRIS_SCORE = 0, FAST_SCORE = 1 };

  /// ORB-SLAM2's parameters: features per frame, pyramid scale factor s > 1 and level count, FAST
  /// thresholds tried first and in cells without corners (grey levels, minThFAST <= iniThFAST).
  /// The affine options are read now (SetAffineOptions() defaults, then AFFINE_ORB_* variables).
  /// Throws std::invalid_argument for out-of-range parameters or a bad environment value.
  ORBextractor(int nfeatures, float scaleFactor, int nlevels, int iniThFAST, int minThFAST);
  ~ORBextractor();
  ORBextractor(const ORBextractor&) = delete;
  ORBextractor& operator=(const ORBextractor&) = delete;

  /// Keypoints and descriptors of a CV_8UC1 image (see the guarantees above); also fills
  /// mvImagePyramid.
  void operator()(cv::InputArray image, cv::InputArray mask, std::vector<cv::KeyPoint>& keypoints,
                  cv::OutputArray descriptors);

  int GetLevels() const;
  float GetScaleFactor() const;
  /// s^i for i = 0 … nlevels−1.
  std::vector<float> GetScaleFactors() const;
  /// 1/s^i.
  std::vector<float> GetInverseScaleFactors() const;
  /// s^(2i), the variance ORB-SLAM2 assigns to a keypoint of octave i (in px²).
  std::vector<float> GetScaleSigmaSquares() const;
  /// 1/s^(2i).
  std::vector<float> GetInverseScaleSigmaSquares() const;

  /// Replaces the defaults that extractors constructed from now on start from (environment
  /// variables still override them); thread-safe. Throws std::invalid_argument for bad options.
  static void SetAffineOptions(const AffineOrbAdapterOptions& options);
  /// The defaults SetAffineOptions() last set (the compiled-in AffineOrbAdapterOptions{} before).
  static AffineOrbAdapterOptions GetAffineOptions();
  /// Process-wide recovery switch, read at every call of operator(): while true, extractors
  /// extract with their options' `recovery` fields (by default three times nfeatures from the image)
  /// instead of nfeatures, max_tilt and view_features; false (the default) restores those.
  /// Extractors whose recovery fields plan the same extraction ignore it. A fork that wants the
  /// recovery mode while tracking is lost adds one line at the top of
  /// Tracking::GrabImageMonocular, GrabImageRGBD and GrabImageStereo:
  ///   ORBextractor::SetRecovering(mState == LOST);
  /// (the state the previous frame left; monocular initialisation, which uses its own extractor
  /// while not initialised, is not affected). Thread-safe (an atomic flag).
  static void SetRecovering(bool recovering);
  /// The state SetRecovering() last set (false before any call).
  static bool Recovering();
  /// The options this extractor uses (defaults with the environment applied at construction).
  AffineOrbAdapterOptions AffineOptions() const;

  /// The original image at each pyramid level of the last frame.
  std::vector<cv::Mat> mvImagePyramid;

 private:
  class Impl;
  Impl* impl_;  // owned; a raw pointer keeps this header free of <memory>
};

}  // namespace ORB_SLAM2
