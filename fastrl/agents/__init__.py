"""Agents: the scripted expert and forward RL on stable-baselines3."""
