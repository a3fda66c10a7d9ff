//! Contact algebra: obstacles, frames, complementarity functions, Tresca regularisation.
//! Pure functions on small fixed-size arrays.
