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

Two implementations of the one loss: ``BCSAC`` on stable-baselines3 (PyTorch) and
``BCSACJax`` on SBX (JAX), whose gradient steps of a vector step run in one jitted loop.
Saved models load as plain SAC of their learner (``rigid-gym evaluate``): the policy is SAC's.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
import torch as th
from stable_baselines3 import SAC, HerReplayBuffer
from stable_baselines3.common.buffers import ReplayBuffer
from stable_baselines3.common.utils import polyak_update
from torch.nn import functional as F


class DemoBuffer:
    """The demonstrations' buffer and the loss's settings, shared by both implementations
    (mixed in before the learner's SAC). bc_weight: the BC term's weight in the actor loss
    (0: plain SAC); bc_batch_size: demo samples per gradient step; q_filter: False keeps every
    demo sample; bc_relabel: HER-relabel the demo samples' goals as the replay buffer does."""

    # what the learner's SAC, after this mixin in the method order, provides
    replay_buffer_kwargs: dict
    replay_buffer_class: type | None
    env: Any
    observation_space: Any
    action_space: Any
    device: Any
    n_envs: int

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
        # the learner's SAC, after this mixin in the method order, defines it
        return super()._excluded_save_params() + ["demo_buffer"]  # type: ignore[misc]


class BCSAC(DemoBuffer, SAC):
    """stable-baselines3's SAC plus the Q-filtered behaviour-cloning term (``DemoBuffer``'s
    arguments)."""

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


def _jax_class():
    """BCSACJax, made on first use so that this module imports where JAX is not installed."""
    import jax
    import jax.numpy as jnp
    import sbx

    class BCSACJax(DemoBuffer, sbx.SAC):
        """SBX's SAC plus the Q-filtered behaviour-cloning term (``DemoBuffer``'s arguments):
        each vector step samples ``gradient_steps`` batches of the replay buffer and of the
        demonstrations and runs every gradient step in one jitted ``fori_loop``, as SBX's SAC
        does (``policy_delay`` 1: the actor steps with the critic)."""

        # set by sbx.SAC's setup: the entropy coefficient's optimiser state and the PRNG key
        ent_coef_state: Any
        key: Any

        def train(self, gradient_steps: int, batch_size: int) -> None:
            use_bc = self.bc_weight > 0 and self.demo_buffer is not None \
                and self.demo_buffer.size() > 0
            if not use_bc:
                return super().train(gradient_steps, batch_size)
            if self.policy_delay != 1:
                raise ValueError("bc_sac on sbx: policy_delay must be 1")
            data = flat_samples(self, self.replay_buffer, batch_size * gradient_steps)
            demo = flat_samples(self, self.demo_buffer, self.bc_batch_size * gradient_steps)
            learning_rate = self.lr_schedule(self._current_progress_remaining)
            self._update_learning_rate(self.policy.actor_state.opt_state,
                                       learning_rate=learning_rate, name="learning_rate_actor")
            self._update_learning_rate(self.policy.qf_state.opt_state,
                                       learning_rate=self.initial_qf_learning_rate or learning_rate,
                                       name="learning_rate_critic")
            (self.policy.qf_state, self.policy.actor_state, self.ent_coef_state, self.key,
             (actor_loss, qf_loss, bc_loss, kept)) = self._train_bc(
                self.tau, self.target_entropy, self.bc_weight, gradient_steps, self.q_filter,
                data, demo[0], demo[1], self.policy.qf_state, self.policy.actor_state,
                self.ent_coef_state, self.key)
            self._n_updates += gradient_steps
            self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
            for name, value in (("actor_loss", actor_loss), ("critic_loss", qf_loss),
                                ("bc_loss", bc_loss), ("bc_kept", kept)):
                self.logger.record(f"train/{name}", float(value))

        @classmethod
        @partial(jax.jit, static_argnames=["cls", "gradient_steps", "q_filter"])
        def _train_bc(cls, tau, target_entropy, bc_weight, gradient_steps, q_filter, data,
                      demo_obs, demo_actions, qf_state, actor_state, ent_coef_state, key):
            batch = data[0].shape[0] // gradient_steps
            demo_batch = demo_obs.shape[0] // gradient_steps

            def one_update(i, carry):
                qf_state, actor_state, ent_coef_state, key, _ = carry
                part = [jax.lax.dynamic_slice_in_dim(x, i * batch, batch) for x in data]
                obs, actions, next_obs, dones, rewards, discounts = part
                qf_state, (qf_loss, _), key = cls.update_critic(
                    actor_state, qf_state, ent_coef_state, obs, actions, next_obs, rewards,
                    dones, discounts, key)
                qf_state = cls.soft_update(tau, qf_state)
                d_obs = jax.lax.dynamic_slice_in_dim(demo_obs, i * demo_batch, demo_batch)
                d_act = jax.lax.dynamic_slice_in_dim(demo_actions, i * demo_batch, demo_batch)
                key, noise_key, dropout_key = jax.random.split(key, 3)
                ent_coef = ent_coef_state.apply_fn({"params": ent_coef_state.params})

                def min_q(observations, actions):
                    return jnp.min(qf_state.apply_fn(qf_state.params, observations, actions,
                                                     rngs={"dropout": dropout_key}), axis=0)[:, 0]

                def actor_loss(params):
                    dist = actor_state.apply_fn(params, obs)
                    sampled = dist.sample(seed=noise_key)
                    log_prob = dist.log_prob(sampled).reshape(-1, 1)
                    q_pi = jnp.min(qf_state.apply_fn(qf_state.params, obs, sampled,
                                                     rngs={"dropout": dropout_key}), axis=0)
                    sac_loss = (ent_coef * log_prob - q_pi).mean()
                    mode = actor_state.apply_fn(params, d_obs).mode()
                    error = ((mode - d_act) ** 2).sum(axis=1)
                    if q_filter:  # keep the samples where the critic rates the demo higher
                        keep = jax.lax.stop_gradient(
                            (min_q(d_obs, d_act) > min_q(d_obs, mode)).astype(jnp.float32))
                    else:
                        keep = jnp.ones_like(error)
                    bc = (keep * error).sum() / jnp.maximum(keep.sum(), 1.0)
                    return sac_loss + bc_weight * bc, (-log_prob.mean(), bc, keep.mean())

                (loss, (entropy, bc, kept)), grads = jax.value_and_grad(
                    actor_loss, has_aux=True)(actor_state.params)
                actor_state = actor_state.apply_gradients(grads=grads)
                ent_coef_state, _ = cls.update_temperature(target_entropy, ent_coef_state,
                                                           entropy)
                return qf_state, actor_state, ent_coef_state, key, (loss, qf_loss, bc, kept)

            zero = jnp.array(0.0)
            carry = (qf_state, actor_state, ent_coef_state, key, (zero, zero, zero, zero))
            return jax.lax.fori_loop(0, gradient_steps, one_update, carry)

    return BCSACJax


def flat_samples(model, buffer, count: int) -> tuple:
    """``count`` samples of ``buffer`` as SBX trains on them: (observations, actions,
    next observations, dones, rewards, discounts) numpy arrays, a Dict observation flattened
    in its space's key order (``prepare_obs``'s)."""
    data = buffer.sample(count, env=model.get_vec_normalize_env())
    keys = list(model.observation_space.keys())
    obs = np.concatenate([data.observations[k].numpy() for k in keys], axis=1)
    next_obs = np.concatenate([data.next_observations[k].numpy() for k in keys], axis=1)
    discounts = np.full(count, model.gamma, dtype=np.float32) if data.discounts is None \
        else data.discounts.numpy().flatten()
    return (obs, data.actions.numpy(), next_obs, data.dones.numpy().flatten(),
            data.rewards.numpy().flatten(), discounts)


def __getattr__(name: str):
    if name == "BCSACJax":  # JAX is imported only when this class is asked for
        globals()[name] = _jax_class()
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
