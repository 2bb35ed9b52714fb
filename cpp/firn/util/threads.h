#pragma once

#include <exception>
#include <memory>
#include <utility>

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

namespace firn {

// The core's own TBB arena, for long work called from a host that shares TBB with Firn (Blender does; the
// Python bindings run every long call through runInCoreArena). Its thread cap applies to it alone, never to
// the host's own parallel work; its priority is low, so the host's parallel work gets TBB's workers first;
// and the workers run its tasks at a lower OS priority (niceness kWorkerNiceness), so the host's UI thread is
// never starved of the processor by a bake running on every core.

constexpr int kWorkerNiceness = 5;

// Caps the threads the core's parallel loops use; 0 lifts the cap (all hardware threads).
void setThreadCount(int count);
int hardwareThreadCount();

// The arena the core's work runs in (replaced, not changed, when the thread count changes).
std::shared_ptr<tbb::task_arena> coreArena();

// Runs `work` on the calling thread inside the core's arena; its parallel loops use the arena's threads.
template <class Work>
auto runInCoreArena(Work &&work) -> decltype(work()) {
    const std::shared_ptr<tbb::task_arena> arena = coreArena();  // alive until the work is done
    return arena->execute(std::forward<Work>(work));
}

// Runs `side` as a task beside `work` (on the calling thread) and returns when both are done. When `work` throws,
// its exception is the one that goes on, whatever `side` did: the task is waited for first (it may write what
// `work`'s caller owns), and its own exception, a second one, is dropped.
template <class Side, class Work>
void runBeside(Side &&side, Work &&work) {
    tbb::task_group beside;
    beside.run(std::forward<Side>(side));
    try {
        work();
    } catch (...) {
        const std::exception_ptr first = std::current_exception();
        try {
            beside.wait();
        } catch (...) {  // the side task's: a second error, after the one that goes on
        }
        std::rethrow_exception(first);
    }
    beside.wait();
}

}  // namespace firn
