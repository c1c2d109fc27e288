"""Fitting the full-scene and background radiance fields to a dataset (scripts/train.py)."""
