#include "firn/util/threads.h"

#include <mutex>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <tbb/info.h>
#include <tbb/task_scheduler_observer.h>

#include "firn/util/error.h"

namespace firn {

namespace {

// Linux keeps a niceness per thread (setpriority on a thread id).
int threadNiceness() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }
bool setThreadNiceness(int niceness) {
    return setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), niceness) == 0;
}

// TBB's worker threads run the core's tasks at a lower priority, so the host's UI thread (and, under a software
// GL driver, its rasterizer threads) get the processor first. A worker leaving the arena gets its priority back
// where the system allows raising it again (root, or RLIMIT_NICE); otherwise it stays lower, which only matters
// when other processes compete for the processor. Threads that call into the core are left alone: their owner
// decides (the add-on lowers its job threads).
class LowerWorkerPriority : public tbb::task_scheduler_observer {
  public:
    explicit LowerWorkerPriority(tbb::task_arena &arena) : tbb::task_scheduler_observer(arena) { observe(true); }
    ~LowerWorkerPriority() override { observe(false); }

    void on_scheduler_entry(bool isWorker) override {
        if (!isWorker) return;
        previous_ = threadNiceness();
        if (previous_ < kWorkerNiceness) setThreadNiceness(kWorkerNiceness);
    }
    void on_scheduler_exit(bool isWorker) override {
        if (isWorker && previous_ < kWorkerNiceness) setThreadNiceness(previous_);
    }

  private:
    static thread_local int previous_;
};

thread_local int LowerWorkerPriority::previous_ = 0;

// An arena and the observer that lowers its workers, made and dropped together.
struct CoreArena {
    explicit CoreArena(int count)
        // One slot is the calling thread's, the rest are TBB's workers. Low priority: when the host's own
        // parallel work wants TBB's workers, it gets them first.
        : arena(count > 0 ? count : tbb::info::default_concurrency(), 1, tbb::task_arena::priority::low),
          lower(arena) {}
    tbb::task_arena arena;
    LowerWorkerPriority lower;
};

std::mutex gMutex;
int gThreadCount = 0;  // 0: all hardware threads
std::shared_ptr<tbb::task_arena> gArena;

std::shared_ptr<tbb::task_arena> makeArena(int count) {
    auto owner = std::make_shared<CoreArena>(count);
    return std::shared_ptr<tbb::task_arena>(owner, &owner->arena);  // keeps the observer alive with the arena
}

}  // namespace

void setThreadCount(int count) {
    if (count < 0) throw InvalidArgument("thread count must be 0 (all cores) or positive");
    std::lock_guard<std::mutex> lock(gMutex);
    if (gArena && count == gThreadCount) return;
    gThreadCount = count;
    gArena = makeArena(count);  // work already running keeps the arena it started in
}

int hardwareThreadCount() { return tbb::info::default_concurrency(); }

std::shared_ptr<tbb::task_arena> coreArena() {
    std::lock_guard<std::mutex> lock(gMutex);
    if (!gArena) gArena = makeArena(gThreadCount);
    return gArena;
}

}  // namespace firn
