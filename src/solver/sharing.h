// Whether a batch of worlds is shared out over the thread pool or stepped on the calling
// thread alone: whichever has cost that batch less, measured as it steps.
//
// Sharing pays only when a batch's work outweighs what it costs to wake the pool's workers
// and split the work, and that differs between machines by an order of magnitude. Where
// cores are independent and a worker wakes within microseconds, far smaller batches should
// gain from a second thread (not measured on the project's machines). On a VM whose two
// vCPUs together run about 1.2-1.6x one of them (two processes at once each ran at 0.6-0.8x
// their speed alone) and whose sleeping worker takes 57-245 us to wake, the Push env's
// 16-copy step (~100 us of solver work) ran at 0.63x shared, 1024 copies at 1.26x. No fixed
// batch size serves both, so each batch measures. A call's cost moves with what its worlds
// do (copies asleep, contacts, resets), so the two ways are compared in pairs of consecutive
// calls, one each way: the first two calls, shared first (a batch stepped in one long call is
// shared, the way that pays for the large batches such calls are made for), then a probe now
// and then (one call the way not chosen, paired with the call before it and the one after).
// The choice is the way the median of the last SAMPLES pairs found cheaper. Probes come
// FIRST_PROBE calls apart at first and after a pair that goes against the choice, and
// otherwise twice as far apart after each probe, up to LAST_PROBE: once settled they cost
// well under 1% (a probe the slower way at 1024 copies: 6.8 ms against 3.4). The clock is read
// twice per call (tens of nanoseconds against a call's microseconds). Which thread steps a
// world never changes a bit of it (step.h), so the choice changes speed only.
#pragma once

#include <cstdint>

namespace rg {

class BatchSharing {
public:
    BatchSharing() { restart(); }

    // Share the next call out over the pool? (Asked only when the pool has several threads
    // and the batch several worlds.)
    bool share() const;

    // The call ran `shared` or not and took `seconds` (wall) for `world_steps` world-steps.
    void record(bool shared, double seconds, int64_t world_steps);

    // The way the last call ran: 0 none recorded, 1 on the calling thread, 2 shared.
    int last() const { return calls_ == 0 ? 0 : last_shared_ ? 2 : 1; }

    // Every call from now on alone (0) or shared (1), or chosen by the timings (-1): to step
    // one way on purpose (tests, comparisons of the two ways). Back to the timings, the choice
    // starts afresh: the next two calls are a new first pair.
    void force(int way);

private:
    static constexpr int64_t FIRST_PROBE = 32, LAST_PROBE = 1024;  // calls between probes
    static constexpr int SAMPLES = 5;  // paired comparisons the choice rests on

    // Nothing measured: the next call shared, the one after it alone (the first pair).
    void restart();

    double ratio_[SAMPLES] = {};  // shared / alone cost of consecutive calls, newest first
    int samples_;                 // how many of ratio_ hold one (at most SAMPLES)
    int64_t calls_ = 0;
    int64_t next_probe_;          // the call that runs the way not chosen
    int64_t interval_;            // calls to the probe after the next
    bool chosen_;                 // share the calls that are not probes
    int forced_ = -1;             // force()
    bool last_shared_ = false;
    double last_cost_;            // s per world-step of the last call; 0: no pair with it
};

}  // namespace rg
