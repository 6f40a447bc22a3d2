"""A scene's seed or fidelity replaced after it was read (:func:`bench.scenes.scene.with_overrides`: the hosts'
``--seed`` through :func:`bench.hosts.scene_sensors.sensors_from_scene`, the pytest plugin's session settings) is
the scene ``biotac-bench run --seed/--fidelity`` runs: read again and validated again, so a seed also places its
slides; a scene changed in code keeps its changes."""

from __future__ import annotations

import dataclasses

from bench.hosts.scene_sensors import sensors_from_scene
from bench.paths import REPO
from bench.scenes.scene import load_scene, with_overrides

#: a scene with slides: their start positions are drawn from the scene's seed
SLIDES = REPO / "fixtures" / "scenes" / "skin_wear.toml"


def test_a_hosts_seed_places_the_scenes_slides_as_runs_seed_does():
    """``bridge``/``cheetah serve --seed 5`` (and a factory's ``seed=5``) slide sensor 1 where ``run --seed 5`` does,
    not where the file's own seed put it; its sensor 2 draws seed 6."""
    as_run = load_scene(SLIDES, {"scene.seed": 5})
    assert as_run.stimuli != load_scene(SLIDES).stimuli
    sensors = sensors_from_scene(load_scene(SLIDES), 2, seed=5)
    assert list(sensors[1].stimuli) == as_run.stimuli
    assert (sensors[1].seed, sensors[2].seed) == (5, 6)
    assert with_overrides(load_scene(SLIDES), {"scene.seed": 5}) == as_run


def test_a_scene_changed_in_code_keeps_its_changes_under_a_new_seed():
    """A scene whose fields were changed after it was read is not read again from its text (that would undo the
    change): its seed is replaced as given."""
    changed = dataclasses.replace(load_scene(SLIDES), duration_s=3.0)
    seeded = with_overrides(changed, {"scene.seed": 5})
    assert (seeded.duration_s, seeded.seed) == (3.0, 5)
    assert with_overrides(changed, {}) is changed
