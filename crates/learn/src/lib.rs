//! Learning: the MDP over `referee::Match`, DQN and PPO on tch.
