//! Frictional contact between rod segments (paper Sec. 3.2).
pub mod broad_phase;
pub mod cone;
pub mod gauss_seidel;
pub mod segment;
