"""``zoetic bench aquarium``: how fast a tank lives, and what happened in it."""

from __future__ import annotations

import dataclasses
import time

from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live, summarize

BOTH = "both"  # ``skills``: the built-in and the learned tank, side by side


def bench_aquarium(
    fishes: int = 10,
    food: int | None = None,
    obstacles: int | None = None,
    seconds: float = 60.0,
    seed: int = 0,
    perception: str = "oracle",
    predator_skills: str | None = None,
    skills: str | None = None,
    plants: str = "static",
    predators: int = 1,
    seeing: int = 1,
) -> dict:
    """Return the realtime factor of the tank (brains, perception and physics together, no
    video; ``perception`` oracle, or vision for the first ``seeing`` of the ``predators``),
    the same world's physics alone, and the run's outcome figures. ``skills``: every fish's
    motor skills ("built-in", "learned" or a repertoire's directory; default the species
    files'), or
    "both": the built-in and the learned tank one after the other, each line under its name,
    with the learned tank's CPU realtime factor over the built-in's. ``plants``: the
    seaweed dynamic (swaying strands) or static (fixed cylinders)."""
    if skills == BOTH:
        out = {
            k: bench_aquarium(
                fishes,
                food,
                obstacles,
                seconds,
                seed,
                perception,
                predator_skills,
                k,
                plants,
                predators,
                seeing,
            )
            for k in ("built-in", "learned")
        }
        cpu = [out[k]["cpu_realtime_factor"] for k in ("learned", "built-in")]
        return out | {"learned_over_built_in_cpu": cpu[0] / cpu[1] if all(cpu) else None}
    cfg, warm = _configs(
        fishes, food, obstacles, seconds, seed, perception, predator_skills, skills, plants
    )
    cfg = dataclasses.replace(cfg, predators=predators, seeing=seeing)
    tank = build_tank(cfg)  # a bad option is refused before the warm-up
    live(build_tank(warm))  # compile, calibrate the motor controllers
    c0 = time.process_time()
    life = live(tank)
    cpu = time.process_time() - c0
    return _figures(cfg, summarize(tank, life), cpu, *_physics_alone(cfg))


def _configs(
    fishes, food, obstacles, seconds, seed, perception, predator_skills, skills, plants
) -> tuple[TankConfig, TankConfig]:
    """Return the benchmarked tank's config and a small one that compiles and calibrates
    the same code first (``bench_aquarium``'s arguments)."""
    # no video: positions recorded once a brain period (the CLI records 20 frames a second)
    cfg = TankConfig(
        fishes=fishes,
        food=food,
        obstacles=obstacles,
        seconds=seconds,
        seed=seed,
        record_period=0.1,
        perception=perception,
        predator_skills=predator_skills,
        skills=skills,
        plants=plants,
    )
    warm = TankConfig(
        fishes=2,
        predators=1,
        food=1,
        obstacles=2,  # a rock and a seaweed clump: compiles the plants' contacts too
        seconds=0.2,
        perception=perception,
        predator_skills=predator_skills,
        skills=skills,
        plants=plants,
    )
    return cfg, warm


def _figures(cfg: TankConfig, s: dict, cpu: float, physics: float, physics_cpu: float) -> dict:
    """Return the benchmark's line: the tank's summary ``s``, its CPU seconds and the wall
    and CPU seconds of its physics alone."""
    seconds, perception = cfg.seconds, cfg.perception

    def per_minute(count: int) -> float | None:
        return 60.0 * count / s["seconds"] if s["seconds"] > 0 else None

    return {
        "scene": f"{cfg.fishes} fishes, {cfg.food} food, {cfg.obstacles} obstacles, {seconds:g} s",
        "perception": perception
        if perception == "oracle"
        else f"{perception} ({cfg.seeing} seeing)",
        "predators": cfg.predators,
        "skills": cfg.skills or "species files",
        "predator_skills": cfg.predator_skills or cfg.skills or "species file",
        "plants": cfg.plants,
        "realtime_factor": s["realtime_factor"],
        "wall_seconds": s["wall_seconds"],
        "physics_only_realtime_factor": seconds / physics if physics > 0 else None,
        # CPU time of this process: what a busy machine's other work does not count against
        "cpu_realtime_factor": seconds / cpu if cpu > 0 else None,
        "physics_only_cpu_realtime_factor": seconds / physics_cpu if physics_cpu > 0 else None,
        "events": s["events"],
        "food_eaten_fraction": s["food_eaten_fraction"],
        "collisions_with_obstacles": s["collisions_with_obstacles"],
        "deepest_into_obstacle_m": s["deepest_into_obstacle_m"],
        "collisions_between_fishes": s["collisions_between_fishes"],
        "deepest_into_fish_m": s["deepest_into_fish_m"],
        # per minute of simulated time: fish against fish, and fish against rock or wall
        "fish_collisions_per_minute": per_minute(s["collisions_between_fishes"]),
        "obstacle_collisions_per_minute": per_minute(s["collisions_with_obstacles"]),
        "avoid_share": s["intention_share"]["avoid"],
        "survivors": s["survivors"],
    }


def _physics_alone(cfg: TankConfig) -> tuple[float, float]:
    """Return the wall and CPU seconds of the same world stepped with the same number of
    calls and no brains: the physics' share of the tank's time."""
    bare = build_tank(cfg)
    t0, c0 = time.perf_counter(), time.process_time()
    steps = bare.world.steps_for(cfg.record_period)
    for _ in range(int(round(cfg.seconds / cfg.record_period))):
        bare.world.step(steps * bare.world.dt, None)
    return time.perf_counter() - t0, time.process_time() - c0
