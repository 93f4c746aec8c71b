"""The products and what builds them from a plan: a LeRobot dataset (`dataset`: the oracle's
verified demos, `produce`, in worker processes, `workers`), a plan alone (`plan_only`), an exam
(`exam`), LIBERO's own initial states as an exam (`canonical`), and what they record (`scenes`,
`provenance`, `card`, `sheet`); `run` picks one."""
