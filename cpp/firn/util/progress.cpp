#include "firn/util/progress.h"

#include <algorithm>
#include <chrono>

#include "firn/util/error.h"

namespace firn {

namespace {
double nowSeconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// Stores `value` in `to` unless it holds more already.
void storeMax(std::atomic<double> &to, double value) {
    double held = to.load();
    while (held < value && !to.compare_exchange_weak(held, value)) {
    }
}
}  // namespace

void Progress::report(double fraction, const std::string &stage) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stage_ = stage;
    }
    report(fraction);
}

void Progress::report(double fraction) {
    fraction_.store(std::clamp(fraction, 0.0, 1.0));
    notify();
}

void Progress::advance(double fraction) {
    storeMax(fraction_, std::clamp(fraction, 0.0, 1.0));
    notify();
}

std::string Progress::stage() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stage_;
}

void Progress::throwIfCancelled() const {
    if (isCancelled()) throw Cancelled();
}

void Progress::notify() {
    if (!callback_) return;
    std::unique_lock<std::mutex> calling(callbackMutex_, std::try_to_lock);
    if (!calling.owns_lock()) return;  // another thread is calling back right now
    const double now = nowSeconds(), fraction = fraction_.load();
    std::string current = stage();
    if (current == lastStage_ && lastCallbackTime_ >= 0.0 && now - lastCallbackTime_ < interval_ && fraction < 1.0) return;
    lastCallbackTime_ = now, lastStage_ = current;
    callback_(fraction, current);
}

void SubProgress::report(double fraction) const {
    if (sideBySide_) sideBySide_->report(step_, fraction);
    else if (parent_) parent_->report(begin_ + (end_ - begin_) * fraction);
}

SubProgress SideBySideProgress::step(std::size_t i) const {
    SubProgress out(parent_, 0.0, 1.0);
    out.sideBySide_ = this, out.step_ = i;
    return out;
}

void SideBySideProgress::report(std::size_t step, double fraction) const {
    if (!parent_) return;
    storeMax(done_[step], std::clamp(fraction, 0.0, 1.0));
    double sum = 0.0;
    for (std::size_t i = 0; i < shares_.size(); ++i) sum += shares_[i] * done_[i].load();
    parent_->advance(begin_ + (end_ - begin_) * sum);
}

}  // namespace firn
