"""Source text of a task runner that counts what goes through a Dask session (maps, submits,
and submits given a future, i.e. a task fed by another task on the workers), for the scripts
the AMLS task tests run in a subprocess of their own."""

COUNTING = """
class Counting:
    def __init__(self, s):
        self.s, self.maps, self.submits, self.chained = s, 0, 0, 0
    def map(self, f, jobs):
        self.maps += 1
        return self.s.map(f, jobs)
    def submit(self, f, *args):
        self.submits += 1
        self.chained += any(type(a).__name__ == "Future" for a in args)
        return self.s.submit(f, *args)
    def done(self, h):
        return self.s.done(h)
    def completed(self, hs):
        return self.s.completed(hs)
    def task_memory(self):
        return self.s.task_memory()
    def counts(self):
        return [self.maps, self.submits, self.chained]
"""
