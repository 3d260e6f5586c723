#pragma once

namespace deli {

// Call before the first LAMMPS instance of a process that no MPI launcher started (deli
// validate, the cross-check tests, the peers' driver run alone). LAMMPS initialises MPI on
// first use, and Open MPI's singleton start then forks an orted daemon, loads every transport
// component and leaves a session folder in /tmp for each process, which later starts scan:
// about 0.5 s of a cross-check's 0.8 s. One process needs none of that, so this asks Open MPI
// (through its environment, before MPI starts) for an isolated singleton that talks only to
// itself. Settings the user made are kept, and under mpirun (or another launcher) nothing is
// changed. Other MPI implementations ignore these variables.
void prefer_single_process_mpi();

}  // namespace deli
