"""What a robot program on the lattice needs, whatever its method: working out where it is
(`localise`), what is around it (`view`), hearing news from beyond its sensing range (`relay`),
and what it knows of its shape (`shape`).

Each works on one step's `swarmshape.core.perception.Perception` of every robot at once, over
arrays, never a loop over robots; none keeps state of its own (a program's memory holds it).
`mean-shift` is built on them; `local-swap` predates them.
"""
