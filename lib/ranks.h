// The processes of a render (docs/design.md §11): one, or the ranks of an MPI job. Every rank
// loads the scene and builds what the passes need; render() divides the passes (or, with fewer
// passes than ranks, each pass's photons or rows) between the ranks and sums their films at
// rank 0 in fixed point, so the image is the one a single process renders, to the bit.
#pragma once

#include <cstdint>
#include <vector>

namespace rs {

class Ranks {
public:
    virtual ~Ranks() = default;
    virtual int rank() const { return 0; }
    virtual int size() const { return 1; }
    // The ranks on this machine (this one included): they share its memory.
    virtual int sizeOnThisMachine() const { return 1; }

    // Every rank calls agree() at the same points of the render, and a failed rank once, in
    // place of the point it did not reach. Returns the lowest rank whose `ok` was false (-1:
    // none) and rank 0's `more`.
    struct Agreement {
        int failedRank = -1;
        bool more = false;
    };
    virtual Agreement agree(bool ok, bool more) { return {ok ? -1 : rank(), more}; }

    // Sums every rank's `values` into rank 0's; the others' are left as they were.
    virtual void sumAtRoot(std::vector<int64_t>& /*values*/) {}
    // Every rank's `values` become rank 0's.
    virtual void broadcast(double* /*values*/, int /*count*/) {}
};

// This process alone.
Ranks& singleProcess();

}  // namespace rs
