"""Train and resume: a run's stages, its learner, callbacks, warm start, evaluation and demonstrations."""
