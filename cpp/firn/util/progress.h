#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <string>

namespace firn {

// Shared between a long computation and whoever watches it (a UI timer, a script).
// The computation reports; the watcher polls or is called back, and may cancel.
// Every member is safe to call from any thread.
class Progress {
  public:
    // Called on each report, from the reporting thread, at most every kCallbackInterval.
    using Callback = std::function<void(double fraction, const std::string &stage)>;

    Progress() = default;
    explicit Progress(Callback callback) : callback_(std::move(callback)) {}

    void report(double fraction, const std::string &stage);
    void report(double fraction);

    double fraction() const { return fraction_.load(); }
    std::string stage() const;

    void cancel() { cancelled_.store(true); }
    bool isCancelled() const { return cancelled_.load(); }
    // Long loops call this between chunks of work; it throws firn::Cancelled.
    void throwIfCancelled() const;

  private:
    void notify();

    std::atomic<double> fraction_{0.0};
    std::atomic<bool> cancelled_{false};
    mutable std::mutex mutex_;
    std::string stage_;
    Callback callback_;
    double lastCallbackTime_ = -1.0;  // s, steady clock
};

// Progress of one step of several: maps [0, 1] onto [begin, end] of the parent.
class SubProgress {
  public:
    SubProgress(Progress *parent, double begin, double end) : parent_(parent), begin_(begin), end_(end) {}
    // A step run beside another that reports: it reports nothing (the parent's fraction would go back and forth)
    // but still stops when the parent is cancelled.
    static SubProgress cancelOnly(Progress *parent) {
        SubProgress out(parent, 0.0, 0.0);
        out.reports_ = false;
        return out;
    }
    void report(double fraction) const {
        if (parent_ && reports_) parent_->report(begin_ + (end_ - begin_) * fraction);
    }
    void throwIfCancelled() const {
        if (parent_) parent_->throwIfCancelled();
    }

  private:
    Progress *parent_;
    double begin_, end_;
    bool reports_ = true;
};

}  // namespace firn
