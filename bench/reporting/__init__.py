"""What a run leaves behind: record.json, report.md, and plots (time traces, spectrograms, sensitivity)."""
