"""Experiments that take long: many runs or a training, one table or curve. Each is a subcommand of ``crowdsim
experiment`` whose module declares its own flags and runs it (``crowdsim.cli.Command``); ``EXPERIMENTS`` gathers
them."""

from ..cli import Command

EXPERIMENTS = (
    Command("ppo", "stable-baselines3 PPO on crowdsim/Navigate-v0 with the tracks observation, against the random "
                   "policy (needs [rl])", "crowdsim.experiments.ppo"),
    Command("train-detector", "AdaBoost and random-forest segment classifiers on labelled airport scans, scored "
                              "against laser_segments on held-out seeds (needs [train])",
            "crowdsim.experiments.train_detector"),
    Command("table2", "seed 000's Table II on the airport over --seeds seeds (from 1), its claims checked",
            "crowdsim.experiments.table2"),
    Command("tune", "Optuna over the pipeline's parameters for MOTA (needs [tune])", "crowdsim.experiments.tune"),
    Command("train-relations", "the svm and forest relation classifiers on tracker output of airport seeds "
                               "1100-1119 (needs [train])", "crowdsim.experiments.training"),
    Command("groups", "the group stage on held-out airport seeds (from 1200): each classifier against SPENCER's, "
                      "each linkage, thresholds, tracker against true tracks", "crowdsim.experiments.groups"),
    Command("train-hog", "the wall cameras' HOG person detector on rendered images of seed 001's room, or the robot "
                         "camera's (needs [train])", "crowdsim.experiments.train_hog"),
    Command("seed001", "seed 001's Tables 2-6, its RJMCMC filter over the laser and the wall cameras in four modes on "
                       "sequences I-III, its claims checked", "crowdsim.experiments.seed001"),
    Command("hog-vs-opencv", "our HOG model against OpenCV's INRIA-trained one on held-out images (needs [compare])",
            "crowdsim.experiments.train_hog", arguments="add_compare_arguments", main="compare_main"),
    Command("seed003", "seed 003's Tables 2-5, its RGB-D detector and tracker on the KTP-like room's five situations "
                       "under four robot motions, in five variants, its claims checked",
            "crowdsim.experiments.seed003"),
)
