//! Monte Carlo reference for the form factor (stub).
