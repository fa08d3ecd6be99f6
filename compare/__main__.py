from .cli import entry

# `python -m compare` = `xval`. Guarded as a script must be for process pools: called at the
# top level unguarded, a map saw an unguarded script and ran in this process, one point at a time
if __name__ == "__main__":
    entry()
