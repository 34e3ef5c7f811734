//! Estimators: the paper's ARX least squares, instrumental variables / SRIVC, output error.
