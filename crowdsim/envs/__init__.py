"""The gymnasium environments, registered on ``import crowdsim``: ``crowdsim/Navigate-v0`` (reach a goal through
the crowd) and ``crowdsim/Follow-v0`` (follow a person), each with a natively batched vector environment."""

from gymnasium.envs.registration import register, registry

for _id, _task in (("crowdsim/Navigate-v0", "navigate"), ("crowdsim/Follow-v0", "follow")):
    if _id not in registry:
        register(_id, entry_point="crowdsim.envs.navigate:CrowdEnv",
                 vector_entry_point="crowdsim.envs.navigate:CrowdVectorEnv", kwargs={"task": _task})
