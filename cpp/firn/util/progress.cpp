#include "firn/util/progress.h"

#include <algorithm>
#include <chrono>

#include "firn/util/error.h"

namespace firn {

namespace {
constexpr double kCallbackInterval = 0.1;  // s: often enough for a progress bar, rare enough to be free

double nowSeconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
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

std::string Progress::stage() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stage_;
}

void Progress::throwIfCancelled() const {
    if (isCancelled()) throw Cancelled();
}

void Progress::notify() {
    if (!callback_) return;
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;  // another thread is reporting right now
    const double now = nowSeconds();
    if (lastCallbackTime_ >= 0.0 && now - lastCallbackTime_ < kCallbackInterval && fraction_.load() < 1.0) return;
    lastCallbackTime_ = now;
    const std::string stage = stage_;
    lock.unlock();
    callback_(fraction_.load(), stage);
}

}  // namespace firn
