from rostool.cli import main

main()
