"""How every command runs, whatever it makes: its command line (`cli`), the checks on where it
writes (`output`), its resumable and locked partial run (`partial`), its worker processes
(`processes`) and the crash points the tests inject (`faults`). Below the generator, so the exam
(eval/) and training (train/) use them without importing it."""
