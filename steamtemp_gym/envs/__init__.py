"""The generic environment, its native vector env and rendering."""

from steamtemp_gym.envs.steam_temp_env import SteamTempEnv
from steamtemp_gym.envs.vector_env import SteamTempVectorEnv

__all__ = ["SteamTempEnv", "SteamTempVectorEnv"]
