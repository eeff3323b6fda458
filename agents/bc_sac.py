"""SAC with a behaviour-cloning loss on demonstrations, filtered by the critic (Nair et al. 2018,
"Overcoming exploration in reinforcement learning with demonstrations").

The demonstrations go into the replay buffer as usual (the critic learns from them) and also
into a buffer of their own, ``demo_buffer`` (``train.add_demonstrations`` fills both). Each
gradient step adds to SAC's actor loss

    bc_weight * mean over demo samples with Q(s, a_demo) > Q(s, pi(s)) of |pi(s) - a_demo|^2

where pi(s) is the deterministic action (the one evaluated), Q the minimum over the critics,
and the demo samples come from ``demo_buffer``. With HER, the demo samples keep the goals the
demonstrator pursued unless ``bc_relabel``: a demo action is the right action for its own goal,
not for a goal relabelled from where the cubes happened to be later. The Q-filter drops the term where the critic already rates the policy's action
above the demonstrator's, so the policy can outgrow the demonstrations.

Saved models load as plain SAC (``rigid-gym evaluate``): the policy is SAC's.
"""

from __future__ import annotations

import numpy as np
import torch as th
from torch.nn import functional as F

from stable_baselines3 import SAC, HerReplayBuffer
from stable_baselines3.common.buffers import ReplayBuffer
from stable_baselines3.common.utils import polyak_update


class BCSAC(SAC):
    """SAC plus a Q-filtered behaviour-cloning term. bc_weight: its weight in the actor loss
    (0: plain SAC); bc_batch_size: demo samples per gradient step; q_filter: False keeps every
    demo sample; bc_relabel: HER-relabel the demo samples' goals as the replay buffer does."""

    def __init__(self, *args, bc_weight: float = 1.0, bc_batch_size: int = 128,
                 q_filter: bool = True, bc_relabel: bool = False, **kwargs):
        self.bc_weight, self.bc_batch_size, self.q_filter = bc_weight, bc_batch_size, q_filter
        self.bc_relabel = bc_relabel
        self.demo_buffer: ReplayBuffer | None = None
        super().__init__(*args, **kwargs)

    def make_demo_buffer(self, size: int):
        """A new, empty ``demo_buffer`` of the replay buffer's kind for ``size`` transitions."""
        kwargs = dict(self.replay_buffer_kwargs)
        buffer_class = self.replay_buffer_class
        assert buffer_class is not None  # SAC's _setup_model sets it
        if issubclass(buffer_class, HerReplayBuffer):
            kwargs["env"] = self.env
            if not self.bc_relabel:
                kwargs["n_sampled_goal"] = 0  # every sample keeps its episode's goal
        self.demo_buffer = buffer_class(
            size, self.observation_space, self.action_space, device=self.device,
            n_envs=self.n_envs, **kwargs)
        return self.demo_buffer

    def _excluded_save_params(self) -> list[str]:
        return super()._excluded_save_params() + ["demo_buffer"]

    def _bc_loss(self) -> tuple[th.Tensor, float]:
        """The filtered behaviour-cloning loss and the fraction of demo samples it kept."""
        assert self.demo_buffer is not None  # train uses the term only with a demo buffer
        demo = self.demo_buffer.sample(self.bc_batch_size, env=self.get_vec_normalize_env())
        action = self.actor(demo.observations, deterministic=True)
        error = ((action - demo.actions) ** 2).sum(dim=1)
        if not self.q_filter:
            return error.mean(), 1.0
        with th.no_grad():
            q_demo = th.cat(self.critic(demo.observations, demo.actions), dim=1).min(dim=1).values
            q_pi = th.cat(self.critic(demo.observations, action), dim=1).min(dim=1).values
            keep = (q_demo > q_pi).float()
        return (keep * error).sum() / keep.sum().clamp(min=1.0), keep.mean().item()

    def train(self, gradient_steps: int, batch_size: int = 64) -> None:
        """SAC's ``train`` (stable-baselines3 2.x) with the BC term added to the actor loss."""
        self.policy.set_training_mode(True)
        optimizers = [self.actor.optimizer, self.critic.optimizer]
        if self.ent_coef_optimizer is not None:
            optimizers += [self.ent_coef_optimizer]
        self._update_learning_rate(optimizers)
        logs: dict[str, list[float]] = {name: [] for name in ("ent_coef", "actor_loss", "critic_loss", "bc_loss",
                                      "bc_kept")}
        use_bc = self.bc_weight > 0 and self.demo_buffer is not None and self.demo_buffer.size()
        assert self.replay_buffer is not None  # SAC's _setup_model makes it

        for gradient_step in range(gradient_steps):
            data = self.replay_buffer.sample(batch_size, env=self.get_vec_normalize_env())
            if self.use_sde:
                self.actor.reset_noise()
            actions_pi, log_prob = self.actor.action_log_prob(data.observations)
            log_prob = log_prob.reshape(-1, 1)

            if self.ent_coef_optimizer is not None and self.log_ent_coef is not None:
                ent_coef = th.exp(self.log_ent_coef.detach())
                assert isinstance(self.target_entropy, float)  # "auto" is resolved by then
                ent_coef_loss = -(self.log_ent_coef * (log_prob + self.target_entropy).detach()
                                  ).mean()
                self.ent_coef_optimizer.zero_grad()
                ent_coef_loss.backward()
                self.ent_coef_optimizer.step()
            else:
                ent_coef = self.ent_coef_tensor
            logs["ent_coef"].append(ent_coef.item())

            with th.no_grad():
                next_actions, next_log_prob = self.actor.action_log_prob(data.next_observations)
                next_q = th.cat(self.critic_target(data.next_observations, next_actions), dim=1)
                next_q = next_q.min(dim=1, keepdim=True).values - ent_coef * next_log_prob.reshape(-1, 1)
                discounts = data.discounts if data.discounts is not None else self.gamma
                target_q = data.rewards + (1 - data.dones) * discounts * next_q
            current_q = self.critic(data.observations, data.actions)
            critic_loss = 0.5 * sum(F.mse_loss(q, target_q) for q in current_q)
            assert isinstance(critic_loss, th.Tensor)  # a sum of at least one critic's loss
            logs["critic_loss"].append(critic_loss.item())
            self.critic.optimizer.zero_grad()
            critic_loss.backward()
            self.critic.optimizer.step()

            q_pi = th.cat(self.critic(data.observations, actions_pi), dim=1).min(dim=1, keepdim=True).values
            actor_loss = (ent_coef * log_prob - q_pi).mean()
            if use_bc:
                bc_loss, kept = self._bc_loss()
                actor_loss = actor_loss + self.bc_weight * bc_loss
                logs["bc_loss"].append(bc_loss.item())
                logs["bc_kept"].append(kept)
            logs["actor_loss"].append(actor_loss.item())
            self.actor.optimizer.zero_grad()
            actor_loss.backward()
            self.actor.optimizer.step()

            if gradient_step % self.target_update_interval == 0:
                polyak_update(self.critic.parameters(), self.critic_target.parameters(), self.tau)
                polyak_update(self.batch_norm_stats, self.batch_norm_stats_target, 1.0)

        self._n_updates += gradient_steps
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        for name, values in logs.items():
            if values:
                self.logger.record(f"train/{name}", np.mean(values))
