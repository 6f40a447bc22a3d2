"""pytest plugin (entry point ``pytest11``, name ``biotac``): :mod:`.fixtures` hands users' tests an emulated sensor, a bridge on a pty, or the Cheetah path."""
