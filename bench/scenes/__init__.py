"""Scene files: the format (TOML), its validation with messages naming field, value and range, and the stimuli a scene describes."""
