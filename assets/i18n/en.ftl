# Vigie console, English. Every message here has its twin in fr.ftl (a test checks).
# Plant texts (signal descriptions) go in the plant folder's i18n/<lang>.ftl.

## Language switch
lang-switch-hover = Language of the console

## Toolbar
mode-production = Production
mode-maintenance = Maintenance
mode-training = Training
mode-maintenance-needs-role = Editing the program needs the maintenance role: log in
sim-pause = Pause
sim-run = Run
sim-step = Step
sim-step-hover = One PLC cycle
sim-speed = Speed
plant-start = Start
plant-start-hover = Plant START button
plant-stop = Stop
plant-stop-hover = Plant STOP button

## State at a glance
state-tripped = TRIPPED
state-stopped = STOPPED
state-manual = MANUAL
state-degraded = DEGRADED
state-idle = IDLE
state-running = RUNNING
state-tripped-hover = The safety filter holds the outputs in their safe state
state-stopped-hover = The diagnosers stopped the plant: check it, then reset them
state-manual-hover = The operator drives the outputs; every command is checked
state-degraded-hover = A sensor is read from its estimate or held as suspect
state-idle-hover = The control program is at rest: press Start to produce
state-running-hover = The control program runs
state-paused = SIMULATION PAUSED
state-unacknowledged = { $n } unacknowledged

## Central panel
tab-synoptic = Synoptic
tab-trends = Trends
tab-trends-hover = The history of any signal over minutes to days

## Trends
trends-range = Range
trends-add = Add a signal…
trends-full = { $n } signals at most
trends-filter = Filter
trends-remove-hover = Remove { $signal } from the trends
trends-export = Export CSV…
trends-export-hover = The changes of these signals over the range, to a file you choose
trends-no-history = No history: the console runs without a data folder (the journal is in memory only).
trends-empty = Add a signal to see its history.
trends-legend = Each row is a signal, high when 1; a solid bar is a signal that changed faster than the screen can show (zoom in). `.cmd` is the output the program commanded, without it the output applied.
trends-now = now
