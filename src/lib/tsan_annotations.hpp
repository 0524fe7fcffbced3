// Happens-before annotations for ThreadSanitizer around oneTBB (internal to src/lib).
// libtbb is not built with ThreadSanitizer, so TSan cannot see the edges TBB creates when it
// hands a task to a worker and joins it. Under TSan the callers state them (release before the
// parallel phase and at the end of each task, acquire at the start of each task and after the
// join); TBB's own internals are covered by test/tsan.supp (race_top only). No-ops otherwise.
#pragma once

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#define GDRHCR_TSAN_ACQUIRE(p) __tsan_acquire(p)
#define GDRHCR_TSAN_RELEASE(p) __tsan_release(p)
#else
#define GDRHCR_TSAN_ACQUIRE(p) ((void)(p))
#define GDRHCR_TSAN_RELEASE(p) ((void)(p))
#endif
