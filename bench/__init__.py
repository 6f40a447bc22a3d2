"""The bench: scenes, the runner, host-side sampling, measurements, claims, reports and the CLI."""
