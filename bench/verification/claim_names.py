"""The claim groups' names, in the order the claims table runs them: what ``biotac-bench claims --help`` lists.

The groups register themselves in :data:`bench.verification.claims.CLAIM_GROUPS` when their modules are imported,
which loads the whole emulator; this list lets ``claims --help`` name them without that (once the registry is
loaded, ``--only`` takes its names from the registry itself).  ``bench/tests/test_cli_startup.py`` checks that the
two agree."""

CLAIM_GROUP_NAMES = ("noise", "scales", "force", "impact", "detection", "false-detection", "vibration", "thermal",
                     "electrodes", "exploration", "sliding", "rig", "texture-properties")
