//! XDMF + HDF5 output, written in parallel (every rank its own rows).
