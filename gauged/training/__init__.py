"""Training of the project's models (needs the `train` extra: torch). Never imported at run time."""
