#include "crosscheck/single_process_mpi.hpp"

#include <cstdlib>
#include <initializer_list>

namespace deli {

void prefer_single_process_mpi() {
  // Open MPI's launchers set OMPI_COMM_WORLD_SIZE, PMIx's set PMIX_RANK, MPICH's hydra
  // PMI_RANK: the process then belongs to a job of several ranks, which needs the transports.
  for (const char* launched : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"}) {
    if (std::getenv(launched) != nullptr) return;
  }
  const int overwrite = 0;  // a value the user set wins
  setenv("OMPI_MCA_ess_singleton_isolated", "1", overwrite);
  setenv("OMPI_MCA_btl", "self", overwrite);
  setenv("OMPI_MCA_pml", "ob1", overwrite);
}

}  // namespace deli
