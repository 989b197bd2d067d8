// Ranks over MPI: agreement is one MPI_Allreduce (MIN) of two integers, the film's reduction
// one MPI_Reduce (SUM) of 64-bit integers per buffer, whose sum does not depend on its order,
// and rank 0's decisions one MPI_Bcast.
#include "mpi_ranks.h"

#include <climits>
#include <cstdlib>
#include <string>

#include "core/error.h"

#ifdef RAYSPLAT_HAVE_MPI
// The C API only: Open MPI's deprecated C++ bindings do not compile without warnings.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace rs::cli {

#ifdef RAYSPLAT_HAVE_MPI

namespace {

class MpiRanks : public Ranks {
public:
    MpiRanks(int* argc, char*** argv) {
        int provided = 0;
        MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);  // only the main thread calls MPI
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
        MPI_Comm local;
        MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
        MPI_Comm_size(local, &local_);
        MPI_Comm_free(&local);
    }
    ~MpiRanks() override { MPI_Finalize(); }

    int rank() const override { return rank_; }
    int size() const override { return size_; }
    int sizeOnThisMachine() const override { return local_; }

    Agreement agree(bool ok, bool more) override {
        // [lowest failed rank, rank 0's "stop"]: the others send INT_MAX, which MIN ignores.
        int mine[2] = {ok ? INT_MAX : rank_, rank_ == 0 ? (more ? 0 : 1) : INT_MAX};
        int all[2];
        MPI_Allreduce(mine, all, 2, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
        return {all[0] == INT_MAX ? -1 : all[0], all[1] == 0};
    }

    void sumAtRoot(std::vector<int64_t>& values) override {
        const int count = int(values.size());
        if (rank_ == 0)
            MPI_Reduce(MPI_IN_PLACE, values.data(), count, MPI_INT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
        else
            MPI_Reduce(values.data(), nullptr, count, MPI_INT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    }

    void broadcast(double* values, int count) override { MPI_Bcast(values, count, MPI_DOUBLE, 0, MPI_COMM_WORLD); }

private:
    int rank_ = 0, size_ = 1, local_ = 1;
};

// mpirun (Open MPI's, or a PMI launcher's) tells its processes so in the environment.
bool startedByMpirun() {
    return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK") || std::getenv("PMI_SIZE");
}

}  // namespace

std::unique_ptr<Ranks> joinMpiJob(int* argc, char*** argv) {
    if (!startedByMpirun()) return nullptr;
    return std::make_unique<MpiRanks>(argc, argv);
}

#else

std::unique_ptr<Ranks> joinMpiJob(int*, char***) {
    const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
    if (size && std::atoi(size) > 1)
        throw Error(ErrorKind::Config, std::string("started by mpirun as ") + size +
                                           " processes, but this raysplat was built without MPI "
                                           "(install libopenmpi-dev and rebuild; meson option mpi)");
    return nullptr;
}

#endif

}  // namespace rs::cli
