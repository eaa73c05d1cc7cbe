#!/usr/bin/env python3
"""How much foveation goes unnoticed? A two-alternative forced-choice experiment with QUEST.

On each trial the observer fixates the cross and sees two intervals: the full-frame reference and
a foveated rendering at the γ chosen by PsychoPy's QuestHandler, in random order; the observer
presses 1 or 2 for the interval that looked degraded. A larger γ makes the AO budget fall faster
with eccentricity (fewer rays, more visible noise and more of the constant ambient). QUEST works
on log10 γ and estimates the γ detected on 82 % of trials (its default threshold, with a guess
rate of 0.5 for 2AFC). PsychoPy's ExperimentHandler writes its standard data files (a wide CSV
and a .psydat) under --out.

    python examples/psychopy/foveation_threshold.py --participant P01
    xvfb-run -a python examples/psychopy/foveation_threshold.py --simulate 3.0 --trials 40

``--simulate GAMMA`` replaces the person with a model observer that looks at the images: it
measures each trial's visible difference between the foveated frame and the reference (the
acuity-weighted RMSE of foveal.compare: errors weighted by the visual acuity at their
eccentricity, Geisler & Perry 1998's falloff) and detects it with QUEST's own Weibull on log10 of
that difference, its threshold set at the difference the frame at γ = GAMMA makes. Frames that do
not differ are never detected (chance), so the experiment can run unattended and a test can check
that QUEST finds GAMMA through the rendered images.

A display at which foveation changes no pixel (a small window: at 320×200 pixels over 47.5 cm
every pixel keeps the reference's value at every γ in QUEST's range) would measure nothing: the
experiment checks the largest γ first and refuses such a geometry, saying so.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

import numpy as np

from session_checks import check_display, check_foveal_inputs


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--participant", default="sim", help="participant id (file names)")
    p.add_argument("--scene", default="builtin:box", help="scene (default builtin:box)")
    p.add_argument("--size", default="840x525", help="stimulus size WxH pixels (default 840x525)")
    p.add_argument("--display", default="47.5,30,60", help="screen W_CM,H_CM,DIST_CM")
    p.add_argument("--max-rays", type=int, default=100, help="n_max (the reference's rays everywhere)")
    p.add_argument("--trials", type=int, default=40, help="trials (default 40)")
    p.add_argument("--start-gamma", type=float, default=2.0, help="QUEST's first guess of the threshold γ")
    p.add_argument("--interval-s", type=float, default=0.75, help="each interval's duration, seconds")
    p.add_argument("--device", default="auto", help="auto, cpu or cuda")
    p.add_argument("--seed", type=int, default=1, help="seed of the interval order and the simulated observer")
    p.add_argument("--simulate", type=float, default=None, metavar="GAMMA", help="a simulated observer with this threshold γ")
    p.add_argument("--out", default="data", help="folder for PsychoPy's data files")
    args = p.parse_args(argv)
    check_args(p, args)
    return args


def check_args(parser, args):
    """Every option, before any rendering or window: one line naming it (a bad one was a traceback,
    or surfaced only once the reference had rendered and the window opened)."""
    try:
        args.w, args.h = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        args.w = args.h = 0
    if not (1 <= args.w <= 16384 and 1 <= args.h <= 16384):
        parser.error(f"--size: expected WxH in pixels (1–16384 each), got {args.size!r}")
    try:
        args.wcm, args.hcm, args.dcm = (float(v) for v in args.display.split(","))
    except ValueError:
        args.wcm = args.hcm = args.dcm = 0.0
    if not all(math.isfinite(v) and v > 0 for v in (args.wcm, args.hcm, args.dcm)):
        parser.error(f"--display: expected three positive numbers W_CM,H_CM,DIST_CM, got {args.display!r}")
    if args.trials < 1:
        parser.error(f"--trials: must be at least 1, got {args.trials}")
    if not args.max_rays >= 1:
        parser.error(f"--max-rays: must be at least 1, got {args.max_rays}")
    if not 1.0 <= args.start_gamma <= MAX_GAMMA:
        parser.error(f"--start-gamma: must be within QUEST's range of γ, [1, {MAX_GAMMA:g}], got {args.start_gamma}")
    if not (math.isfinite(args.interval_s) and args.interval_s > 0):
        parser.error(f"--interval-s: must be positive seconds, got {args.interval_s}")
    if args.simulate is not None and not (math.isfinite(args.simulate) and args.simulate > 0):
        parser.error(f"--simulate: the threshold γ must be positive, got {args.simulate}")
    if not args.participant or os.sep in args.participant or args.participant in (".", ".."):
        parser.error(f"--participant: {args.participant!r} names the data files: no path separator")
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        parser.error(f"--out: {args.out} is a file; give a folder")
    summary = os.path.join(args.out, f"{args.participant}_summary.json")
    if os.path.exists(summary):  # a participant's earlier session: never written over
        parser.error(f"--participant {args.participant}: {summary} holds a session already; give another --participant or --out")
    args.scene_object = check_foveal_inputs(parser, args.scene, None, args.device)
    check_display(parser)


# QUEST's psychometric function (Watson & Pelli 1983, as PsychoPy's QuestHandler uses it)
BETA, DELTA, GUESS, P_THRESHOLD = 3.5, 0.01, 0.5, 0.82
MAX_GAMMA = 12.0  # QUEST's range of γ: 1 … 12


def weibull(log_gamma: float, log_threshold: float) -> float:
    """P(correct) at log10 γ for an observer whose P_THRESHOLD point is at log_threshold."""
    # QUEST places its threshold where P = P_THRESHOLD: shift the Weibull so that holds
    p0 = (P_THRESHOLD - GUESS) / (1 - GUESS - DELTA)
    shift = math.log10(-math.log(1 - p0)) / BETA  # the Weibull is at p0 of its range when x − xt = shift
    x = log_gamma - log_threshold + shift
    return DELTA * GUESS + (1 - DELTA) * (1 - (1 - GUESS) * math.exp(-10 ** (BETA * x)))


def model_observer_p(difference: float, threshold_difference: float) -> float:
    """The model observer's P(correct) for a frame whose visible difference from the reference is
    `difference`: QUEST's Weibull on log10 of the difference, at P_THRESHOLD where it equals
    `threshold_difference`; no difference is chance (the guess rate)."""
    if not difference > 0:
        return GUESS
    return weibull(math.log10(difference), math.log10(threshold_difference))


def to_psychopy(image: np.ndarray) -> np.ndarray:
    """Linear RGB → sRGB in PsychoPy's float range [−1, 1], rows bottom-up (as ImageStim takes them)."""
    import foveal
    return foveal.linear_to_srgb(image, low=-1.0, high=1.0, bottom_up=True)


def main(argv=None) -> int:
    args = parse_args(argv)
    import foveal
    from psychopy import core, data, event, visual

    w, h = args.w, args.h
    wcm, hcm, dcm = args.wcm, args.hcm, args.dcm
    display = foveal.Display(wcm, hcm, dcm, w, h)
    renderer = foveal.Renderer(args.scene_object, device=args.device)
    gaze = (w / 2.0, h / 2.0)
    reference_linear = renderer.render(size=(w, h), gaze=gaze, mode="full", max_rays=args.max_rays, display=display).image.copy()
    reference = to_psychopy(reference_linear)

    def foveated_at(gamma: float):
        return renderer.render(size=(w, h), gaze=gaze, max_rays=args.max_rays, gamma=gamma, display=display)

    def visible_difference(image: np.ndarray) -> float:
        return foveal.compare(image, reference_linear, gaze=gaze, display=display)["acuity_weighted_rmse"]

    # A geometry at which foveation changes nothing measures nothing: check QUEST's largest γ first
    if np.array_equal(foveated_at(MAX_GAMMA).image, reference_linear):
        raise SystemExit(
            f"foveation_threshold: at {w}x{h} pixels on a {wcm:g}x{hcm:g} cm display seen from {dcm:g} cm "
            f"({display.pixels_per_degree:.1f} px/deg), the foveated frame at γ = {MAX_GAMMA:g} (the largest QUEST tries) is "
            f"identical to the reference: foveation changes no pixel, so no threshold could be measured. Use a larger "
            f"--size (840x525 differs at every γ on this display) or another --max-rays.")
    threshold_difference = visible_difference(foveated_at(args.simulate).image) if args.simulate is not None else None

    os.makedirs(args.out, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    quest = data.QuestHandler(startVal=math.log10(args.start_gamma), startValSd=0.4, pThreshold=P_THRESHOLD,
                              nTrials=args.trials, beta=BETA, delta=DELTA, gamma=GUESS, grain=0.005,
                              minVal=math.log10(1.0), maxVal=math.log10(MAX_GAMMA), name="gamma")
    exp = data.ExperimentHandler(name="foveation_threshold", extraInfo={"participant": args.participant, "scene": args.scene,
                                                                          "simulated_threshold": args.simulate},
                                 dataFileName=os.path.join(args.out, f"{args.participant}_foveation_threshold"))
    exp.addLoop(quest)

    win = visual.Window((w, h), units="pix", fullscr=False, allowGUI=False, color=(0, 0, 0))
    stim = visual.ImageStim(win, image=reference, size=(w, h), units="pix", interpolate=False)
    cross = visual.ShapeStim(win, vertices="cross", size=12, lineColor=(1, -1, -1), fillColor=(1, -1, -1))
    prompt = visual.TextStim(win, text="Which interval was degraded? 1 or 2", height=18, color=(1, 1, 1))
    clock = core.Clock()
    duration = 0.0 if args.simulate is not None else args.interval_s

    for log_gamma in quest:
        gamma = 10 ** log_gamma
        frame = foveated_at(gamma)
        foveated = to_psychopy(frame.image)
        degraded_first = bool(rng.random() < 0.5)
        for image in ((foveated, reference) if degraded_first else (reference, foveated)):
            stim.image = image
            clock.reset()
            while True:  # at least one frame per interval, `duration` seconds with a person
                stim.draw()
                cross.draw()
                win.flip()
                if clock.getTime() >= duration:
                    break
            win.flip()
        prompt.draw()
        win.flip()
        if args.simulate is not None:
            # The model observer sees the images: this frame's visible difference against the threshold's
            difference = visible_difference(frame.image)
            correct = bool(rng.random() < model_observer_p(difference, threshold_difference))
            exp.addData("visible_difference", difference)
            answer = (1 if degraded_first else 2) if correct else (2 if degraded_first else 1)
            rt = float("nan")
        else:
            keys = event.waitKeys(keyList=["1", "2", "escape"], timeStamped=clock)
            if keys[0][0] == "escape":
                break
            answer, rt = int(keys[0][0]), keys[0][1]
            correct = answer == (1 if degraded_first else 2)
        quest.addResponse(int(correct))
        exp.addData("gamma", gamma)
        exp.addData("degraded_interval", 1 if degraded_first else 2)
        exp.addData("answer", answer)
        exp.addData("rt_s", rt)
        exp.addData("ao_rays_per_pixel", frame.stats["ao_rays_per_pixel"]["mean"])
        exp.nextEntry()

    win.close()
    estimate = 10 ** quest.mean()
    summary = {"participant": args.participant, "trials": quest.thisTrialN + 1, "threshold_gamma": estimate,
               "threshold_gamma_sd_log10": quest.sd(), "simulated_threshold_gamma": args.simulate,
               "p_threshold": P_THRESHOLD, "observer": "model (acuity-weighted RMSE)" if args.simulate is not None else "person",
               "threshold_visible_difference": threshold_difference}
    with open(os.path.join(args.out, f"{args.participant}_summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    exp.close()  # writes the .csv and .psydat
    print(f"foveation_threshold: {summary['trials']} trials, QUEST threshold γ = {estimate:.2f} (sd {quest.sd():.3f} log10)"
          + (f", simulated observer's γ = {args.simulate:g}" if args.simulate is not None else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
