#include "firn/util/progress.h"

#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "firn/util/error.h"

namespace firn {

TEST(Progress, ClampsAndKeepsStage) {
    Progress progress;
    progress.report(0.25, "sampling");
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.25);
    EXPECT_EQ(progress.stage(), "sampling");
    progress.report(7.0);
    EXPECT_DOUBLE_EQ(progress.fraction(), 1.0);
    EXPECT_EQ(progress.stage(), "sampling");
}

TEST(Progress, CancelMakesWorkThrow) {
    Progress progress;
    EXPECT_NO_THROW(progress.throwIfCancelled());
    progress.cancel();
    EXPECT_THROW(progress.throwIfCancelled(), Cancelled);
}

TEST(Progress, CallbackSeesFinalReportFromAnyThread) {
    std::vector<double> seen;
    std::mutex m;
    Progress progress([&](double f, const std::string &) {
        std::lock_guard<std::mutex> lock(m);
        seen.push_back(f);
    });
    std::thread worker([&] {
        for (int i = 0; i <= 1000; ++i) progress.report(i / 1000.0);
    });
    worker.join();
    ASSERT_FALSE(seen.empty());
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);  // the end is always reported
    EXPECT_LT(seen.size(), 1001u);       // throttled
}

TEST(SubProgress, MapsOntoParentRange) {
    Progress progress;
    SubProgress(&progress, 0.5, 0.75).report(0.5);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.625);
}

// A step run beside another (bake: thin snow traced beside the light) reports nothing, but stops when cancelled.
TEST(SubProgress, CancelOnlyReportsNothingButStopsWhenCancelled) {
    Progress progress;
    progress.report(0.3);
    const SubProgress quiet = SubProgress::cancelOnly(&progress);
    quiet.report(0.9);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.3);
    EXPECT_NO_THROW(quiet.throwIfCancelled());
    progress.cancel();
    EXPECT_THROW(quiet.throwIfCancelled(), Cancelled);
}

}  // namespace firn
