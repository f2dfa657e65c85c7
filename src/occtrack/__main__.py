from occtrack.cli import main

raise SystemExit(main())
