// The ranks of an MPI job (lib/ranks.h), when raysplat is built with Open MPI (meson option
// `mpi`) and started by mpirun; docs/design.md §11.
#pragma once

#include <memory>

#include "ranks.h"

namespace rs::cli {

// Joins the MPI job this process was started in, or returns nullptr: not started by mpirun
// (the binary then runs as one process, unchanged), or built without MPI. The job ends with
// the object.
std::unique_ptr<Ranks> joinMpiJob(int* argc, char*** argv);

}  // namespace rs::cli
