//! The PETSc binding layer: the only module with `unsafe`.
