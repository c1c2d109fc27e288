"""Synthetic datasets with ground truth, rendered from Mitsuba XML scenes (scripts/make_dataset.py)."""
