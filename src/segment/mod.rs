//! From photo to mask: decoding, orientation, downscaling and object segmentation.
