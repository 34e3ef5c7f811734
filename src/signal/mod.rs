//! Input design (doublet, 3-2-1-1, multisine, chirp), resampling, filtering, differentiation.
