"""Limits of a scene that other parts check without loading the scene machinery (and the emulator behind it):
:mod:`bench.scenes.scene` re-exports them."""

#: sensors a scene can describe: the bridge firmware and the Cheetah adapter serve at most 5
MAX_SENSORS = 5
