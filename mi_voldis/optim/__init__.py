"""The optimisation driver shared by fitting and every manipulation task."""
