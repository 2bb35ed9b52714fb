#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace firn {

// Shared between a long computation and whoever watches it (a UI timer, a script).
// The computation reports; the watcher polls or is called back, and may cancel.
// Every member is safe to call from any thread.
class Progress {
  public:
    // Called on each report, from the reporting thread, at most every `interval` (s) but on every new stage.
    using Callback = std::function<void(double fraction, const std::string &stage)>;
    static constexpr double kCallbackInterval = 0.1;  // s: often enough for a progress bar, rare enough to be free

    Progress() = default;
    // interval 0: every report calls back (tests that follow each one), but while another thread's callback runs.
    explicit Progress(Callback callback, double interval = kCallbackInterval)
        : callback_(std::move(callback)), interval_(interval) {}

    void report(double fraction, const std::string &stage);
    void report(double fraction);
    // As report, but the fraction only goes forwards: reporters on several threads (SideBySideProgress).
    void advance(double fraction);

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
    mutable std::mutex mutex_;  // the stage
    std::string stage_;
    Callback callback_;
    double interval_ = kCallbackInterval;
    // One callback at a time, each reading the fraction when it starts (so callbacks see what advance stored in
    // order); the callback's own calls to stage(), fraction() and cancel() do not take it.
    std::mutex callbackMutex_;
    double lastCallbackTime_ = -1.0;  // s, steady clock
    std::string lastStage_;           // the last callback's
};

class SideBySideProgress;

// Progress of one step of several: maps [0, 1] onto [begin, end] of the parent.
class SubProgress {
  public:
    SubProgress(Progress *parent, double begin, double end) : parent_(parent), begin_(begin), end_(end) {}
    void report(double fraction) const;
    void throwIfCancelled() const {
        if (parent_) parent_->throwIfCancelled();
    }

  private:
    friend class SideBySideProgress;
    Progress *parent_;
    double begin_, end_;
    const SideBySideProgress *sideBySide_ = nullptr;  // a step of it (step_), which maps the fraction
    std::size_t step_ = 0;
};

// Steps run side by side (bake: thin snow traced beside the light), each given its share of [begin, end] of the
// parent: the parent moves by the sum of each step's share times its fraction done. A step's fraction never goes
// back (its parallel loop's reports may land out of order), nor does the parent's (Progress::advance: the two
// steps' sums may land out of order).
class SideBySideProgress {
  public:
    SideBySideProgress(Progress *parent, double begin, double end, std::vector<double> shares)
        : parent_(parent), begin_(begin), end_(end), shares_(std::move(shares)), done_(shares_.size()) {}
    // Step i's progress: it reports its own fraction, 0 to 1, and stops when the parent is cancelled.
    SubProgress step(std::size_t i) const;

  private:
    friend class SubProgress;
    void report(std::size_t step, double fraction) const;

    Progress *parent_;
    double begin_, end_;
    std::vector<double> shares_;                       // of [begin, end], per step, adding up to 1
    mutable std::vector<std::atomic<double>> done_;  // per step: its fraction, the most it reported
};

}  // namespace firn
