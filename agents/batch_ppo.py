"""PPO over a natively batched rigid_gym vector env, in JAX: the ``batch`` learner.

    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=256, reward_type="shaped", stagger=True)
    model = BatchPPO("MultiInputPolicy", envs, seed=0, n_steps=32, batch_size=1024)
    model.learn(3_000_000)
    model.save("model.zip")        # a stable-baselines3 PPO zip: SB3's PPO.load reads it

PPO (Schulman et al. 2017) with SB3's defaults where not named (clipped ratio 0.2, GAE,
advantages normalised per minibatch, value loss weight 0.5, gradient norm 0.5, Adam with
eps 1e-5, a state-independent log standard deviation, orthogonal initialisation, tanh
networks of separate actor and critic). What differs from SB3's PPO is the pace: the rollout
reads the vector env's batched arrays directly (no per-env info dicts, no VecEnv wrappers),
the policy acts on all copies in one jitted call per vector step, and the whole update
(``n_epochs`` passes over shuffled minibatches) is one jitted call per rollout. Observations
are normalised by running statistics of the rollouts (as SB3's VecNormalize, without the
clipping), which ``save`` folds into the first layers, so the saved policy reads raw
observations. Truncated episodes are bootstrapped with the value of their last observation.

``save`` writes a stable-baselines3 PPO zip (MultiInputPolicy, ``net_arch`` for actor and
critic, tanh), so ``rigid-gym evaluate``, ``record`` and ``load_model`` load it as any SB3
PPO; the zip also holds this learner's training state (``STATE_ENTRY``: parameters, Adam's
moments, observation statistics, random key, env steps), which SB3 ignores and ``load`` reads
to resume. The callbacks of ``rigid_gym.agents.train`` (evaluations, checkpoints) run through
SB3's callback interface: ``on_step`` after every vector step, ``on_rollout_end`` after every
update.
"""

from __future__ import annotations

import os

# one XLA thread, as the runs of the results table (agents/table.py's ONE_THREAD); set
# before JAX is first imported, which is where the flag is read
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false "
                                   "intra_op_parallelism_threads=1")

import io
import itertools
import pickle
import zipfile
from functools import partial
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax

STATE_ENTRY = "batch_ppo_state.pkl"
"""The zip entry with the training state (SB3's loader reads only its own entries)."""
VARIANCE_FLOOR = 1e-4
"""Added to the observation variances before normalising, m^2 or (m/s)^2: a constant entry
(a goal's height) maps to 0 instead of to noise times 1e4."""


def flatten(observation: dict, keys: tuple[str, ...]) -> np.ndarray:
    """A Dict observation, batched (B, ...) per key, as (B, D) float32, keys in ``keys``
    order (the Dict space's, which is the order SB3's CombinedExtractor concatenates)."""
    return np.concatenate([np.asarray(observation[k], dtype=np.float32).reshape(
        len(observation[keys[0]]), -1) for k in keys], axis=1)


def init_mlp(key, sizes: list[int], last_scale: float) -> list[dict]:
    """Dense layers of ``sizes`` (in, hidden..., out), orthogonal weights (gain sqrt 2, the
    last ``last_scale``) and zero biases, as SB3 initialises PPO's networks."""
    layers = []
    keys = jax.random.split(key, len(sizes) - 1)
    for k, (n_in, n_out) in enumerate(itertools.pairwise(sizes)):
        gain = last_scale if k == len(sizes) - 2 else np.sqrt(2.0)
        w = jax.nn.initializers.orthogonal(gain)(keys[k], (n_in, n_out), jnp.float32)
        layers.append({"w": w, "b": jnp.zeros(n_out, jnp.float32)})
    return layers


def mlp(layers: list[dict], x):
    """tanh between the layers, none after the last."""
    for layer in layers[:-1]:
        x = jnp.tanh(x @ layer["w"] + layer["b"])
    return x @ layers[-1]["w"] + layers[-1]["b"]


def log_prob(mean, log_std, action):
    """Diagonal Gaussian log density (..., A) -> (...)."""
    return jnp.sum(-0.5 * ((action - mean) / jnp.exp(log_std)) ** 2 - log_std
                   - 0.5 * np.log(2 * np.pi), axis=-1)


@jax.jit
def act(params, mean, std, x, x_final, key):
    """Sample actions for normalised observations of raw ``x`` (B, D); also the values of
    ``x`` and of ``x_final`` (B, D: the last observations of the episodes that ended the
    step before). Returns action (B, A), log_prob (B,), value (B,), final value (B,), key."""
    key, noise_key = jax.random.split(key)
    z, z_final = (x - mean) / std, (x_final - mean) / std
    mu = mlp(params["pi"], z)
    action = mu + jnp.exp(params["log_std"]) * jax.random.normal(noise_key, mu.shape)
    return (action, log_prob(mu, params["log_std"], action), mlp(params["vf"], z)[:, 0],
            mlp(params["vf"], z_final)[:, 0], key)


def ppo_loss(params, batch, clip_range, ent_coef, vf_coef):
    """PPO's clipped surrogate loss plus value and entropy terms for one minibatch."""
    mu = mlp(params["pi"], batch["z"])
    logp = log_prob(mu, params["log_std"], batch["actions"])
    ratio = jnp.exp(logp - batch["log_probs"])
    adv = batch["advantages"]
    adv = (adv - adv.mean()) / (adv.std() + 1e-8)
    policy_loss = -jnp.mean(jnp.minimum(ratio * adv, jnp.clip(ratio, 1 - clip_range,
                                                               1 + clip_range) * adv))
    value_loss = jnp.mean((batch["returns"] - mlp(params["vf"], batch["z"])[:, 0]) ** 2)
    entropy = jnp.sum(params["log_std"] + 0.5 * np.log(2 * np.pi * np.e))
    approx_kl = jnp.mean((ratio - 1) - (logp - batch["log_probs"]))
    return policy_loss + vf_coef * value_loss - ent_coef * entropy, approx_kl


@partial(jax.jit, static_argnames=("optimizer", "n_epochs", "batch_size", "clip_range",
                                   "ent_coef", "vf_coef"))
def update(params, opt_state, data, key, *, optimizer, n_epochs, batch_size, clip_range,
           ent_coef, vf_coef):
    """``n_epochs`` passes over ``data`` (arrays of N rows) in shuffled minibatches of
    ``batch_size`` (N // batch_size of them per pass); returns params, opt_state, the mean
    approximate KL of the last pass, key."""
    n = data["z"].shape[0]
    n_batches = n // batch_size

    def step(carry, indices):
        params, opt_state = carry
        batch = {k: v[indices] for k, v in data.items()}
        grads, kl = jax.grad(ppo_loss, has_aux=True)(params, batch, clip_range, ent_coef,
                                                    vf_coef)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), kl

    def epoch(carry, epoch_key):
        order = jax.random.permutation(epoch_key, n)[:n_batches * batch_size]
        carry, kls = jax.lax.scan(step, carry, order.reshape(n_batches, batch_size))
        return carry, kls.mean()

    key, *epoch_keys = jax.random.split(key, n_epochs + 1)
    (params, opt_state), kls = jax.lax.scan(epoch, (params, opt_state), jnp.stack(epoch_keys))
    return params, opt_state, kls[-1], key


class BatchPPO:
    """PPO on a rigid_gym vector env (``gym.make_vec``; see the module docstring).

    policy: "MultiInputPolicy" (the only one; the name SB3's PPO takes). env: a rigid_gym
    vector env (``RigidGymVectorEnv``, SAME_STEP autoreset). n_steps: vector steps per
    rollout; batch_size: minibatch rows (n_steps * num_envs must hold at least one);
    n_epochs: passes over a rollout; gamma, gae_lambda: discount and GAE's lambda;
    learning_rate: Adam's; clip_range: PPO's ratio clip; ent_coef, vf_coef: the loss's
    weights of entropy and value; max_grad_norm: gradients clipped to this global norm;
    policy_kwargs: {"net_arch": [widths]} (the actor's and the critic's hidden layers),
    {"log_std_init": float}; seed: the parameters', the actions' and the envs' seed.
    """

    def __init__(self, policy: str, env, *, seed: int = 0, n_steps: int = 32,
                 batch_size: int = 1024, n_epochs: int = 8, gamma: float = 0.95,
                 gae_lambda: float = 0.95, learning_rate: float = 3e-4, clip_range: float = 0.2,
                 ent_coef: float = 0.0, vf_coef: float = 0.5, max_grad_norm: float = 0.5,
                 policy_kwargs: dict | None = None, verbose: int = 0):
        from stable_baselines3.common.logger import Logger

        if policy != "MultiInputPolicy":
            raise ValueError(f"BatchPPO: policy must be 'MultiInputPolicy', got {policy!r}")
        policy_kwargs = dict(policy_kwargs or {})
        net_arch = policy_kwargs.pop("net_arch", [64, 64])
        log_std_init = float(policy_kwargs.pop("log_std_init", 0.0))
        if policy_kwargs or not (isinstance(net_arch, list) and net_arch
                                 and all(isinstance(w, int) and w > 0 for w in net_arch)):
            raise ValueError("BatchPPO: policy_kwargs takes net_arch (a list of positive "
                             f"widths, the actor's and the critic's) and log_std_init; got "
                             f"net_arch {net_arch!r} and {sorted(policy_kwargs)}")
        self.env = env
        self.n_envs = env.num_envs
        if n_steps * self.n_envs < batch_size:
            raise ValueError(f"BatchPPO: a rollout of n_steps {n_steps} x {self.n_envs} envs "
                             f"is shorter than one minibatch (batch_size {batch_size})")
        self.observation_space = env.single_observation_space
        self.action_space = env.single_action_space
        self.keys = tuple(self.observation_space.spaces)
        self.seed = int(seed)
        self.n_steps, self.batch_size, self.n_epochs = int(n_steps), int(batch_size), \
            int(n_epochs)
        self.gamma, self.gae_lambda = float(gamma), float(gae_lambda)
        self.learning_rate, self.clip_range = float(learning_rate), float(clip_range)
        self.ent_coef, self.vf_coef = float(ent_coef), float(vf_coef)
        self.max_grad_norm = float(max_grad_norm)
        self.net_arch, self.log_std_init = list(net_arch), log_std_init
        self.verbose = verbose
        self.optimizer = optax.chain(optax.clip_by_global_norm(self.max_grad_norm),
                                     optax.adam(self.learning_rate, eps=1e-5))
        size = sum(int(np.prod(self.observation_space[k].shape)) for k in self.keys)
        actions = int(np.prod(self.action_space.shape))
        key, pi_key, vf_key = jax.random.split(jax.random.PRNGKey(self.seed), 3)
        self.params = {"pi": init_mlp(pi_key, [size, *self.net_arch, actions], 0.01),
                       "vf": init_mlp(vf_key, [size, *self.net_arch, 1], 1.0),
                       "log_std": jnp.full(actions, log_std_init, jnp.float32)}
        self.opt_state = self.optimizer.init(self.params)
        self.key = key
        self.obs_count = 0.0
        self.obs_mean = np.zeros(size)
        self.obs_var = np.ones(size)
        self.num_timesteps = 0
        self.approx_kl = 0.0
        self.logger = Logger(folder=None, output_formats=[])
        self.observation: dict | None = None
        """The envs' current observations (after the first reset)."""
        self.sb3_model: Any = None
        """The stable-baselines3 PPO that ``save`` fills, made at the first save."""

    def settings(self) -> dict:
        """The PPO arguments this model was made with (SB3's names), but the policy's."""
        return {"n_steps": self.n_steps, "batch_size": self.batch_size,
                "n_epochs": self.n_epochs, "gamma": self.gamma, "gae_lambda": self.gae_lambda,
                "learning_rate": self.learning_rate, "clip_range": self.clip_range,
                "ent_coef": self.ent_coef, "vf_coef": self.vf_coef,
                "max_grad_norm": self.max_grad_norm}

    def get_env(self):
        """None: the envs are no SB3 VecEnv (SB3's callbacks read this)."""
        return

    def normaliser(self) -> tuple[np.ndarray, np.ndarray]:
        """The observations' mean and standard deviation (D,), float32."""
        return (self.obs_mean.astype(np.float32),
                np.sqrt(self.obs_var + VARIANCE_FLOOR).astype(np.float32))

    def observe(self, rows: np.ndarray) -> None:
        """Fold a rollout's observations (N, D) into the running mean and variance (Chan et
        al.'s parallel update, as SB3's RunningMeanStd)."""
        n, mean, var = len(rows), rows.mean(axis=0, dtype=np.float64), rows.var(
            axis=0, dtype=np.float64)
        total = self.obs_count + n
        delta = mean - self.obs_mean
        self.obs_var = (self.obs_var * self.obs_count + var * n
                        + delta ** 2 * self.obs_count * n / total) / total
        self.obs_mean = self.obs_mean + delta * n / total
        self.obs_count = total

    def learn(self, total_timesteps: int, callback=None, progress_bar: bool = False,
              reset_num_timesteps: bool = True):
        """Train for ``total_timesteps`` more env steps (whole vector steps; the last rollout
        may end early), calling ``callback`` (SB3's BaseCallback) as SB3's PPO does."""
        from stable_baselines3.common.callbacks import CallbackList

        if reset_num_timesteps:
            self.num_timesteps = 0
        end = self.num_timesteps + int(total_timesteps)
        callback = callback if callback is not None else CallbackList([])
        callback.init_callback(self)
        callback.on_training_start(locals(), globals())
        if self.observation is None:
            self.observation, _ = self.env.reset(seed=self.seed)
        b, d = self.n_envs, len(self.obs_mean)
        while self.num_timesteps < end:
            steps = min(self.n_steps, -(-(end - self.num_timesteps) // b))
            callback.on_rollout_start()
            buffers = {"x": np.zeros((steps, b, d), np.float32),
                       "actions": np.zeros((steps, b) + self.action_space.shape, np.float32),
                       "log_probs": np.zeros((steps, b), np.float32),
                       "values": np.zeros((steps, b), np.float32),
                       "rewards": np.zeros((steps, b), np.float32),
                       "dones": np.zeros((steps, b), bool)}
            mean, std = self.normaliser()
            assert self.observation is not None
            x = flatten(self.observation, self.keys)
            x_final, truncated_before = x, np.zeros(b, bool)
            for t in range(steps):
                action, logp, value, final_value, self.key = act(
                    self.params, mean, std, x, x_final, self.key)
                if t > 0:  # bootstrap the episodes truncated in the step before
                    buffers["rewards"][t - 1] += self.gamma * np.where(
                        truncated_before, np.asarray(final_value), 0.0)
                action = np.asarray(action)
                buffers["x"][t], buffers["actions"][t] = x, action
                buffers["log_probs"][t], buffers["values"][t] = logp, value
                observation, reward, terminated, truncated, infos = self.env.step(
                    np.clip(action, self.action_space.low, self.action_space.high))
                buffers["rewards"][t] = reward
                buffers["dones"][t] = terminated | truncated
                truncated_before = truncated & ~terminated
                x = flatten(observation, self.keys)
                x_final = x
                if truncated_before.any():
                    x_final = x.copy()
                    for i in np.flatnonzero(truncated_before):
                        x_final[i] = flatten({k: v[None] for k, v in
                                              infos["final_obs"][i].items()}, self.keys)[0]
                self.observation = observation
                self.num_timesteps += b
                if not callback.on_step():
                    return self
            _, _, last_value, final_value, self.key = act(self.params, mean, std, x, x_final,
                                                          self.key)
            buffers["rewards"][-1] += self.gamma * np.where(truncated_before,
                                                            np.asarray(final_value), 0.0)
            advantages = self.advantages(buffers, np.asarray(last_value))
            n = steps * b
            data = {"z": (buffers["x"].reshape(n, d) - mean) / std,
                    "actions": buffers["actions"].reshape(n, -1),
                    "log_probs": buffers["log_probs"].reshape(n),
                    "advantages": advantages.reshape(n),
                    "returns": (advantages + buffers["values"]).reshape(n)}
            if n >= self.batch_size:
                self.params, self.opt_state, kl, self.key = update(
                    self.params, self.opt_state, data, self.key, optimizer=self.optimizer,
                    n_epochs=self.n_epochs, batch_size=self.batch_size,
                    clip_range=self.clip_range, ent_coef=self.ent_coef, vf_coef=self.vf_coef)
                self.approx_kl = float(kl)
            self.observe(buffers["x"].reshape(n, d))
            callback.on_rollout_end()
        callback.on_training_end()
        return self

    def advantages(self, buffers: dict, last_value: np.ndarray) -> np.ndarray:
        """GAE(gamma, lambda) of a rollout (T, B), the episodes' ends cutting the sums."""
        rewards, values, dones = buffers["rewards"], buffers["values"], buffers["dones"]
        advantages = np.zeros_like(rewards)
        running = np.zeros(rewards.shape[1], np.float32)
        next_value = last_value
        for t in reversed(range(len(rewards))):
            live = 1.0 - dones[t]
            delta = rewards[t] + self.gamma * next_value * live - values[t]
            running = delta + self.gamma * self.gae_lambda * live * running
            advantages[t] = running
            next_value = values[t]
        return advantages

    def predict(self, observation: dict, state=None, episode_start=None,
                deterministic: bool = True):
        """SB3's ``predict``: actions (A,) for one observation or (B, A) for a batch, clipped
        to the action space; (actions, None)."""
        single = np.asarray(observation[self.keys[0]]).ndim == len(
            self.observation_space[self.keys[0]].shape)
        batch = {k: np.asarray(v)[None] if single else np.asarray(v)
                 for k, v in observation.items()}
        mean, std = self.normaliser()
        z = (flatten(batch, self.keys) - mean) / std
        params = jax.tree.map(np.asarray, self.params)
        for layer in params["pi"][:-1]:
            z = np.tanh(z @ layer["w"] + layer["b"])
        action = z @ params["pi"][-1]["w"] + params["pi"][-1]["b"]
        if not deterministic:
            action = action + np.exp(params["log_std"]) * np.random.default_rng().standard_normal(
                action.shape)
        action = np.clip(action, self.action_space.low, self.action_space.high)
        return (action[0] if single else action), None

    def folded_layers(self, part: str) -> list[dict]:
        """The ``part`` network (pi or vf) reading raw observations: the normalisation
        (x - mean) / std folded into its first layer's weights and bias (numpy)."""
        layers = jax.tree.map(lambda a: np.asarray(a, np.float64), self.params[part])
        mean, std = self.normaliser()
        first = layers[0]
        first["b"] = first["b"] - (mean / std) @ first["w"]
        first["w"] = first["w"] / std[:, None]
        return layers

    def save(self, path: str | Path) -> None:
        """An SB3 PPO zip of the policy (``folded_layers``) with the training state
        (``STATE_ENTRY``) added."""
        import torch
        from stable_baselines3 import PPO

        from .vec_env import SB3VecEnv

        if self.sb3_model is None:  # on this env's spaces (made, never stepped)
            self.sb3_model = PPO("MultiInputPolicy", SB3VecEnv(self.env), seed=self.seed,
                                 device="cpu", **self.settings(), policy_kwargs={
                                     "net_arch": {"pi": self.net_arch, "vf": self.net_arch},
                                     "activation_fn": torch.nn.Tanh,
                                     "log_std_init": self.log_std_init})
        model = self.sb3_model
        torch_state = model.policy.state_dict()
        for part, hidden, head in (("pi", "mlp_extractor.policy_net", "action_net"),
                                   ("vf", "mlp_extractor.value_net", "value_net")):
            layers = self.folded_layers(part)
            names = [f"{hidden}.{2 * k}" for k in range(len(layers) - 1)] + [head]
            for name, layer in zip(names, layers):
                torch_state[f"{name}.weight"] = torch.as_tensor(layer["w"].T, dtype=torch.float32)
                torch_state[f"{name}.bias"] = torch.as_tensor(layer["b"], dtype=torch.float32)
        torch_state["log_std"] = torch.as_tensor(np.array(self.params["log_std"]))
        model.policy.load_state_dict(torch_state)
        model.num_timesteps = self.num_timesteps
        model.save(path)
        arrays = jax.tree.map(np.asarray, {"params": self.params, "opt_state": self.opt_state,
                                           "key": self.key})
        state = {**arrays, "settings": self.settings(), "seed": self.seed,
                 "obs_count": self.obs_count, "obs_mean": self.obs_mean,
                 "obs_var": self.obs_var, "num_timesteps": self.num_timesteps,
                 "net_arch": self.net_arch, "log_std_init": self.log_std_init}
        with zipfile.ZipFile(path, "a") as archive:
            archive.writestr(STATE_ENTRY, pickle.dumps(state))

    @classmethod
    def load(cls, path: str | Path, env, device: str = "cpu", **kwargs) -> BatchPPO:
        """A model saved by ``save`` on ``env``, its training state restored, to train on.
        ``kwargs``: passed on to the constructor (verbose)."""
        with zipfile.ZipFile(path) as archive:
            if STATE_ENTRY not in archive.namelist():
                raise ValueError(f"BatchPPO.load: {path} holds no {STATE_ENTRY} (a model "
                                 "saved by stable-baselines3, not by this learner)")
            state = pickle.load(io.BytesIO(archive.read(STATE_ENTRY)))
        model = cls("MultiInputPolicy", env, seed=state["seed"], **state["settings"],
                    policy_kwargs={"net_arch": state["net_arch"],
                                   "log_std_init": state["log_std_init"]}, **kwargs)
        model.params = jax.tree.map(jnp.asarray, state["params"])
        model.opt_state = jax.tree.map(jnp.asarray, state["opt_state"])
        model.key = jnp.asarray(state["key"])
        model.obs_count, model.obs_mean, model.obs_var = (state["obs_count"],
                                                          state["obs_mean"], state["obs_var"])
        model.num_timesteps = int(state["num_timesteps"])
        return model
