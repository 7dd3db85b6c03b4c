from p105cli.cli import run

run()
