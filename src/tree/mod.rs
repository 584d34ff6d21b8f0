//! Trees: semantic masks, the tree similarity loss (paper eq. 3) and the tree-structured GA.
