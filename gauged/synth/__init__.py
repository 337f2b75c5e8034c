"""Synthetic data: recordings of moving dials (the dial renderer lives in gauged/training/dial_renderer.py)."""
