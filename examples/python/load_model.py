"""Load a model library at run time and use its model by name, as a built-in one: a robot the
repository does not ship, derived and compiled by ``make model``, with no rebuild of toolconf.

    make model IR=generated/panda.json OUT=/tmp/models/panda     # or DESC=your_robot.toml
    python examples/python/load_model.py /tmp/models/panda --name panda_lib \\
        1.384,-0.0037,0.0037,0.1675,0.0357,0.0361,0.0022,7.7e-4,-7.1e-4,7.1e-4,0.055,0,0.3684

The library is the folder ``make model`` wrote (or its .so); ``--name`` loads it under another
name (a library of a built-in model must be renamed). The last argument is a tool's parameters
in the model's order. ``TOOLCONF_MODEL_PATH`` loads libraries at ``import toolconf`` instead.
"""

import argparse

import toolconf


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("library")
    parser.add_argument("params", help="the tool's parameters, comma-separated")
    parser.add_argument("--name", default=None)
    args = parser.parse_args()

    # Opens the library, checks its ABI, symbols and metadata, and registers its model.
    name = toolconf.load_model(args.library, name=args.name)
    model = toolconf.models()[name]
    print(f"{name}: {model['dof']} joints; parameters {', '.join(model['parameters'])}")

    # Every function now takes the model by name: its confidence and an episode on each task.
    params = [float(v) for v in args.params.split(",")]
    for task in ("position", "velocity", "acceleration"):
        c = toolconf.confidence(name, params, task)
        e = toolconf.simulate(name, params, task)
        print(f"{task:<13} ln|Pi^U| {c['logdet']!r:<20} task error {e['task_error']!r:<22} "
              f"int F dt {e['free_energy']!r}")


if __name__ == "__main__":
    main()
