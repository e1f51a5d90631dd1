"""One module per group of commands: each command's `cmd_` function and its `add_` parser
builder; harness/cli/main.py assembles them."""
