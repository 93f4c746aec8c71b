"""Taking an exam and judging it: the battery that runs a policy on an exam's rows in a simulator
(`battery`), the scorer of the logs (`score`), the report's files (`report`) and the cached
shortcut baseline (`baseline`).
"""
