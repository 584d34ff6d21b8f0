//! Optimisers: Adam, the memetic algorithm (GA + Adam local search) and their schedules.
