"""Running a scene: the host sampler (vendor timing over SPI) and the runner that streams sensor → peripheral → sampler in chunks."""
