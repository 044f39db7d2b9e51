// GraspProbe: slip of a held body relative to the two hands, the hands' vertical force against
// its weight, held or dropped (design note in GraspProbe.h).

#include "hapto/experiments/GraspProbe.h"

#include "hapto/core/Finite.h"
#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/Runtime.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hapto::experiments {
namespace {

bool positiveFinite(double v) {
    return std::isfinite(v) && v > 0.0;
}

bool finiteSample(const GraspSample& s) {
    return finite(s.bodyM) && finite(s.handAM) && finite(s.handBM) && finite(s.forceAN) &&
           finite(s.forceBN);
}

/// The body's centre of mass relative to the hands' midpoint (m).
Vec3 offsetOf(const GraspSample& s) {
    return s.bodyM - 0.5 * (s.handAM + s.handBM);
}

} // namespace

GraspProbe::GraspProbe(const GraspProbeSettings& settings) : mSettings(settings) {
    if (!positiveFinite(settings.massKg) || !positiveFinite(settings.gravityMPerS2) ||
        !positiveFinite(settings.dropSlipM)) {
        throw std::invalid_argument("GraspProbe: mass (" + std::to_string(settings.massKg) +
                                    " kg), gravity and drop slip must be finite and > 0");
    }
    if (!finite(settings.up) || std::abs(glm::length(settings.up) - 1.0) > 1e-9) {
        throw std::invalid_argument("GraspProbe: `up` must be a unit vector");
    }
}

bool GraspProbe::begin(const GraspSample& sample) {
    if (!finiteSample(sample)) {
        ++mNonFinite;
        return false;
    }
    mBegun = true;
    mOffset0 = offsetOf(sample);
    mMaxSlipM = 0.0;
    mLastSlipM = 0.0;
    mErrors.clear();
    return true;
}

double GraspProbe::slipM(const GraspSample& sample) const {
    return mBegun ? glm::length(offsetOf(sample) - mOffset0) : 0.0;
}

double GraspProbe::forceError(const GraspSample& sample) const {
    const double weightN = mSettings.massKg * mSettings.gravityMPerS2;
    const double supportN = -glm::dot(sample.forceAN + sample.forceBN, mSettings.up);
    return std::abs(supportN - weightN) / weightN;
}

void GraspProbe::add(const GraspSample& sample) {
    if (!mBegun) {
        return;
    }
    if (!finiteSample(sample)) {
        ++mNonFinite;
        return;
    }
    mLastSlipM = slipM(sample);
    mMaxSlipM = std::max(mMaxSlipM, mLastSlipM);
    mErrors.push_back(forceError(sample));
}

GraspFigures GraspProbe::figures() const {
    GraspFigures f;
    f.maxSlipM = mMaxSlipM;
    f.finalSlipM = mLastSlipM;
    f.samples = mErrors.size();
    f.nonFinite = mNonFinite;
    if (!mErrors.empty()) {
        f.forceErrorMedian = median(mErrors);
        f.forceErrorWorst = *std::max_element(mErrors.begin(), mErrors.end());
    }
    f.held = f.samples > 0 && f.finalSlipM <= mSettings.dropSlipM;
    return f;
}

std::optional<GraspSample> graspSampleOf(const Runtime& runtime, std::size_t body,
                                         std::size_t handA, std::size_t handB) {
    const BodyPoseTable* poses = runtime.bodyPoses();
    if (poses == nullptr || body >= poses->size() || handA >= runtime.deviceCount() ||
        handB >= runtime.deviceCount()) {
        return std::nullopt;
    }
    ContactReport a, b;
    if (!runtime.lastTick(handA, a) || !runtime.lastTick(handB, b)) {
        return std::nullopt;
    }
    GraspSample s;
    s.bodyM = poses->read(body).centerOfMass;
    s.handAM = a.devicePoint;
    s.handBM = b.devicePoint;
    s.forceAN = a.force;
    s.forceBN = b.force;
    return s;
}

} // namespace hapto::experiments
