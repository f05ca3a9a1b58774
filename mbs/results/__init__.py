"""What a run leaves: the Result and its output probes, the contact records, the HDF5
result file written while the run goes, and checkpoints (a run's state as named arrays)."""
