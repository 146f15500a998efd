"""Where and how work runs: the Ray connection, the compute device, file locks and progress bars."""
