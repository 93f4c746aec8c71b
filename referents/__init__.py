"""Referent types: the ways an instruction can name its target. Each built-in type is one
declarative spec (`<type>.yaml`) and one small module (`<type>.py`) keeping to the type contract
(referents/contract.py); `referents.registry` finds and loads them, and a type's spec for another
world than its own is data in `in_worlds/<world>/<type>.yaml`. This package's `__init__` imports
nothing: its modules import one another."""
