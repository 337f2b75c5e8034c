"""Evaluation of models and readings against labelled data (numpy only; no torch)."""
