"""Campaigns of independent runs: fault × scene × seed through firmware and host driver."""
