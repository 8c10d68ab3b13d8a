"""The benchmarks of ``crowdsim bench``: the hot parts and the whole loop (``parts``), the crowd beside JuPedSim
(``sim``), every sensor (``sensors``), the evaluation (``eval``), the gym environments (``env``) and dataset
generation (``dataset``), the speed figures beside an older checkout's (``speed``), and the floors under those not met
(``floors``). Each is a subcommand whose module declares its own flags and runs it
(``crowdsim.cli.Command``); ``BENCHMARKS`` gathers them."""

from ..cli import Command

BENCHMARKS = (
    Command("loop", "every part and the airport loop (the default)", "crowdsim.bench.parts"),
    Command("sim", "the crowd simulator at 100, 1000 and 5000 agents side by side with JuPedSim's social force model",
            "crowdsim.bench.sim"),
    Command("sensors", "each sensor's cost with 100 and 500 people, batched rays, and the robot's sensor mix against "
                       "real time", "crowdsim.bench.sensors"),
    Command("eval", "the evaluation's frames/s on 5000 frames of 80 persons", "crowdsim.bench.eval"),
    Command("env", "environment steps/s, one env and the vector envs", "crowdsim.bench.env"),
    Command("dataset", "a dataset episode's frames/s and bytes per frame", "crowdsim.bench.dataset"),
    Command("speed", "the loop's, the crowd's and the environments' speed in CPU time, side by side with an older "
                     "checkout's (--against DIR)", "crowdsim.bench.speed"),
    Command("floors", "for the speed targets not met, the CPU of the work each figure cannot shed and the figure it "
                      "allows", "crowdsim.bench.floors"),
)
