// ORB-SLAM2's ORBextractor interface implemented by affine_orb (see ORBextractor.h); the work is
// done by the implementation shared with the ORB-SLAM3 adapter, affine_orb_adapter/core.hpp.
#include "ORBextractor.h"

#include <cstddef>
#include <optional>
#include <utility>

#include "affine_orb_adapter/core.hpp"

namespace ORB_SLAM2 {

namespace {

constexpr const char* kWho = "ORB_SLAM2::ORBextractor";

affine_orb::adapters::DefaultOptionsStore& defaults() {
  static affine_orb::adapters::DefaultOptionsStore store;
  return store;
}

affine_orb::adapters::RecoverySwitch& recovery_switch() {
  static affine_orb::adapters::RecoverySwitch flag;
  return flag;
}

}  // namespace

class ORBextractor::Impl : public affine_orb::adapters::AdapterCore {
 public:
  using AdapterCore::AdapterCore;
};

ORBextractor::ORBextractor(int nfeatures, float scaleFactor, int nlevels, int iniThFAST, int minThFAST)
    : impl_(new Impl(kWho, affine_orb::OrbSlam2Keypoints{}, {nfeatures, scaleFactor, nlevels, iniThFAST, minThFAST},
                     affine_orb::adapters::apply_environment(defaults().get()))) {
  mvImagePyramid.resize(static_cast<std::size_t>(nlevels));
}

ORBextractor::~ORBextractor() { delete impl_; }

void ORBextractor::operator()(cv::InputArray image, cv::InputArray mask, std::vector<cv::KeyPoint>& keypoints,
                              cv::OutputArray descriptors) {
  std::optional<affine_orb::adapters::AdapterFrame> frame = impl_->run(image.getMat(), mask.getMat(), recovery_switch().get());
  if (!frame) return;
  keypoints = std::move(frame->keypoints);
  affine_orb::adapters::write_descriptors(frame->descriptors, descriptors);
  mvImagePyramid = std::move(frame->pyramid);
}

int ORBextractor::GetLevels() const { return impl_->levels(); }
float ORBextractor::GetScaleFactor() const { return impl_->scale_factor(); }
std::vector<float> ORBextractor::GetScaleFactors() const { return impl_->scales().factors; }
std::vector<float> ORBextractor::GetInverseScaleFactors() const { return impl_->scales().inverse_factors; }
std::vector<float> ORBextractor::GetScaleSigmaSquares() const { return impl_->scales().sigma2; }
std::vector<float> ORBextractor::GetInverseScaleSigmaSquares() const { return impl_->scales().inverse_sigma2; }

void ORBextractor::SetAffineOptions(const AffineOrbAdapterOptions& options) { defaults().set(options); }
AffineOrbAdapterOptions ORBextractor::GetAffineOptions() { return defaults().get(); }
void ORBextractor::SetRecovering(bool recovering) { recovery_switch().set(recovering); }
bool ORBextractor::Recovering() { return recovery_switch().get(); }
AffineOrbAdapterOptions ORBextractor::AffineOptions() const { return impl_->affine_options(); }

}  // namespace ORB_SLAM2
