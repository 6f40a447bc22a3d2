"""The experiment's design figures that the command line shows in its help: D ch. 6's pilot textures, a pilot's
worth of trials, and the ablation variants.  Plain data with no imports, so that ``biotac-bench --help`` need not
load the trial machinery (:mod:`bench.experiments.trials` and :mod:`bench.experiments.experiment` re-export
them)."""

#: D ch. 6's pilot: ten dissimilar textures (library numbers), the default of ``[pilot] textures``
D_PILOT_TEXTURES = (10, 30, 43, 46, 47, 84, 87, 100, 38, 58)
#: D's pilot: 10 textures × 6 repetitions of every movement, so one movement's share of it is 60 trials
PILOT_WORTH_TRIALS = 10 * 6
#: ``explore --ablation NAME``: what the variant is, and the experiment fields it overrides as a function of the
#: experiment (so "doubled" doubles whatever the experiment file set)
ABLATIONS = {
    "smooth-skin": ("a skin without fingerprints", lambda spec: {"fingerprints": False}),
    "unreplaced-wear": ("skin wear on, never replaced", lambda spec: {"wear": True, "replace_skin": False}),
    "fewer-trials": ("2 training trials", lambda spec: {"training_trials": 2}),
    "double-noise": ("every sensor noise source doubled", lambda spec: {"noise_scale": 2.0 * spec.noise_scale}),
    # D ch. 6's stepper "background noise that was not consistent from trial to trial", at a level chosen before
    # the run: the sensor's own resting PAC noise (1.4 bits = 0.52 Pa), ×/÷ e^0.5 from trial to trial
    "stepper-noise": ("the rig's stepper background: 0.52 Pa RMS median, varying from trial to trial",
                      lambda spec: {"stepper_noise_Pa": 0.52}),
}
