// The MPI job a process belongs to, as a Communicator (nestlight/converters/communicator.h).
// Built only where MPI is found (the nestlight_mpi target; NESTLIGHT_HAVE_MPI is defined for its
// users): Open MPI from Debian, installed by scripts/setup.sh.
#pragma once

#include <memory>

#include "nestlight/converters/communicator.h"

namespace nestlight {

// MPI_COMM_WORLD. The first call initialises MPI (only the calling thread makes MPI calls);
// MPI is finalised at exit. Throws nestlight::Error when the process was not started by mpirun
// in a way MPI can join.
std::unique_ptr<Communicator> mpiWorld();

}  // namespace nestlight
