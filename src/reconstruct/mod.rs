//! The reconstruction pipeline: cameras from masks, coarse-to-fine fit, evaluation.
