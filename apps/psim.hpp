#pragma once
// psim's command line (psim.cpp): the whole of two programs, psim and psim-mpi, which differ only
// in where the mpi engine runs (particle/processes.hpp): psim delegates it (main.cpp), psim-mpi
// has it (mpi_main.cpp).
int psim_main(int argc, char** argv);
