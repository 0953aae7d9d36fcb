from rostool._entry import main

main()
