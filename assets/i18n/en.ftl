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
synoptic-whole-plant = Whole plant
synoptic-area-hover = One area of the plant at a time, readable; ⚠ marks the area of the trip

## Trends
trends-1-min = 1 min
trends-10-min = 10 min
trends-1-h = 1 h
trends-8-h = 8 h
trends-1-day = 1 day
trends-7-days = 7 days
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

## Unprotected plant
unprotected-banner = UNPROTECTED: no safety constraint, the filter lets every command through

## Toolbar: manual mode, reset, re-initialisation, login
manual-leave = Leave manual
manual-leave-hover = Back to the program, restarted from its initial steps
manual-enter = Manual…
manual-enter-hover = Drive the actuators by hand, every command through the filter
manual-enter-disabled-hover = Not while the filter holds the plant, nor on a live link
reset = Reset
reset-hover = Operator reset of the safety filter
reinit = Re-initialise…
reinit-hover = When the reset is refused because the program or an observer still believes what a transient made it believe: after a check of the plant (emptied, or every item where a sensor shows it), the program back to its initial steps, the sensors taken as read
reinit-disabled-hover = Only after a trip, on the emulator (on a live link the PLC's program is re-initialised on the PLC)
logout = Log out
login = Log in…
login-hover = Operator role until a maintenance, trainer or administrator login
plant-picker-hover = Open another plant folder (its reference program; the session starts over)

## Dialogs
cancel = Cancel
login-title = Log in to the console
login-no-accounts = No account in the data folder yet: an administrator creates them with `vigie user add NAME --role maintenance` (the password on standard input).
login-user = User
login-password = Password
login-submit = Log in
manual-confirm-title = Drive the plant by hand?
manual-confirm-text = The control program stops being scanned and the outputs stay as they are. You then switch each actuator on or off, or jog it while the button is held. Every command is checked against the safety constraints first: one that would break a constraint is refused with the reason and never reaches the plant. Leaving manual mode restarts the program from its initial steps.
manual-confirm-enter = Enter manual mode
reinit-title = Re-initialise after a check of the plant
reinit-text = The control program goes back to its initial steps, as at the start of a shift, the sensors are taken as read and the trip ends. The filter checks the next commands as any other, and the diagnosers decide nothing with certainty until each model is back in its initial state.
reinit-empty-first = Empty the plant first: take every item off by hand, fallen ones included (the initial steps expect no item half-way). Every observer then restarts empty.
reinit-emulator = On the emulator, the emulated items are taken off for you.
reinit-leave-in-place = Or leave the items in place, each where a sensor shows it, none between the sensors: an observer is then cleared only where the sensors leave no room for its item, and the program may stop again on an item it does not expect.
reinit-emptied = Plant emptied: re-initialise
reinit-items-left = Items left in place: re-initialise

## Bypass
bypass-banner = BYPASS: { $id }{ $what } is not enforced until { $until } ({ $min } min { $s } s left), by { $by }: { $reason }
bypass-end = End bypass of { $id }
bypass-title = Bypass a constraint
bypass-needs-role = Bypassing a safety constraint needs the maintenance role: log in.
bypass-reason = Bypass reason
bypass-now = Bypass now
bypass-now-hover = The filter stops enforcing this constraint until the time is up

## Manual mode
manual-title = Manual mode
manual-note = Every command is checked against the safety constraints; a refused one never reaches the plant.
manual-on = ON
manual-off = OFF
manual-set-on = { $id } ON
manual-set-off = { $id } OFF
manual-jog = Jog { $id }
manual-jog-hover = ON while held

## Status line
status-removed = , { $n } taken off
status-boxes = { $scenario } — boxes: { $created } created, { $delivered } delivered, { $damaged } damaged{ $removed }
status-actions = { $scenario } — elementary actions: { $done } completed, { $faults } faults
status-items = items: { $placed } placed, { $out } out (delivered or taken)

## Synoptic banners
banner-level = Level { $level } — trip { $ids } at { $time }
banner-replay = REPLAY at { $time } (live: { $now })
banner-trip = TRIP { $ids } — the safety filter holds the plant

## Next step after a trip
next-title = What to do now (stopped at { $time })
next-why = 1. Why: { $text }.
next-check = 2. Check on the machine: { $where }.
next-reset-possible = 3. Reset is possible now: press Reset, then Start if the program was stopped.
next-reset-refused = 3. Reset is refused now ({ $reason }). Once the cause is gone (the item has moved on, the sensor reads right), press Reset; if it stays refused, check the plant and Re-initialise…

## Explanation
level-0 = 0 Current state
level-1 = 1 Projection
level-2 = 2 Before stop
level-3 = 3 Advanced
level-4 = 4 Hypothesis
expl-title = Explanation
expl-no-trip = No trip: the plant runs within its safety constraints.
expl-action-stop = Stopped by the elementary-action monitor (no constraint tripped): { $why }. The alarm's detail names what to check; repair, then Reset: the program restarts from its initial steps.
expl-violation-at = Violation at { $time } (monitor mode: the plant was not stopped)
expl-trip-at = Trip at { $time }
expl-as-written = as written: { $id } = { $notation }
expl-level = Level { $level }
expl-nothing = Nothing to report at this level.
expl-choose-level = Choose a level to draw it on the synoptic.
expl-save-report-as = Save report as…
expl-report-folder = Report folder
expl-export-report = Export incident report

## Alarms
prio-urgent = URGENT
prio-high = HIGH
prio-medium = MEDIUM
alarms-title = Alarms
alarms-show-shelved = show shelved
alarms-ack-all = Acknowledge all ({ $n })
alarms-none = No active alarm.
alarms-previous = ◀ Previous
alarms-page = Page { $page } of { $pages }
alarms-next = Next ▶
alarms-ack-page = Acknowledge page
alarm-unack = UNACK
alarm-ack = ACK
alarm-cleared-unack = CLEARED-UNACK
alarm-normal = NORMAL
alarm-first-out = FIRST OUT
alarm-shelved-until = (shelved until { $until }: { $reason })
alarm-detail = Detail
alarm-acknowledged-at = acknowledged at { $time }: { $note }
alarm-note-hint = note
alarm-acknowledge = Acknowledge #{ $id }
alarm-unshelve = Unshelve #{ $id }
alarm-shelve = Shelve #{ $id }…
alarm-shelve-safety = A safety alarm (trip, hazard, specification error, live link) is never shelved
shelve-reason = Reason
shelve-reason-hint = why (required)
shelve-now = Shelve #{ $id } now
shelve-needs-reason = Shelving needs a reason

## Alarm performance
kpi-rate = Rate: { $last } in the last 10 min (average { $average }, peak { $peak })
kpi-flood = ALARM FLOOD
kpi-title = Alarm performance
kpi-summary = { $total } alarms in { $intervals } intervals of 10 min; { $floods } in flood (more than { $limit } alarms)
kpi-chattering = Chattering (3 or more within a minute): { $sources }

## Alarm history
history-title = Alarm history ({ $n })
history-search = Search
history-every-kind = every kind
history-every-priority = every priority
history-count = { $n } of { $total }
history-export = Export alarms CSV
history-save-as = Save alarms as…
history-cleared = , cleared { $time }
history-ack = , ack { $time }
history-more = … { $n } more: narrow the search or export

## Journal
journal-title = Journal
journal-written-to = written to { $path }
journal-csv-file = CSV file
journal-export-csv = Export CSV
journal-export-csv-hover = Written under the data folder
journal-save-as = Save journal as…
journal-exports-under = Exports go under { $path }

## What the console says and journals (the journal keeps the English text and the
## message id, and shows an entry in the language shown)
say-session = console opened on { $scenario }
say-login = { $user } logged in ({ $role })
login-wrong = unknown user or wrong password
say-login-locked = Login locked for { $s } s after { $n } failed attempts
say-login-refused = Login refused: { $error }
say-logout = { $user } logged out
say-program-exported = program { $name } (version { $version }) exported as PLCopen XML to { $path }
say-program-export-refused = the program on screen does not compile ({ $problems } problems): nothing exported
say-program-export-failed = cannot export the program to { $path }: { $error }
say-logged-out = Logged out: operator role
say-mode = mode { $mode }
say-ack = alarm { $id } acknowledged: { $note }
say-ack-refused = acknowledge refused: { $error }
say-ack-all = { $n } alarm(s) acknowledged
say-ack-together = alarms { $list } acknowledged together: { $note }
say-shelve = alarm { $id } shelved for { $minutes } min: { $reason }
say-shelve-refused = Shelving refused: { $error }
say-unshelve = alarm { $id } unshelved
say-unshelve-refused = unshelve refused: { $error }
say-language = language { $lang }
say-restart = restart: { $scenario }
say-restarted = restarted
say-restart-failed = restart failed: { $error }
say-compiled = program compiled
say-compile-failed = compilation failed
say-nothing-to-verify = nothing to verify: the edit does not compile
say-no-trip = no trip to report
say-report-written = report written to { $path }; capturing the levels…
say-report = incident report { $path }
say-report-failed = report failed: { $error }
say-png-failed = PNG failed: { $error }
say-report-complete = incident report complete in { $path }
say-report-no-png = report Markdown in { $path }; PNG capture unavailable here
say-alarms-exported = { $n } alarms exported to { $path }
say-alarms-export-failed = alarm export to { $path } failed: { $error }
say-trend-exported = { $n } changes exported to { $path }
say-trend-export-failed = trend export to { $path } failed: { $error }

say-verifying = verifying the constraint set…
say-verify-cannot-start = cannot start the verification: { $error }
say-verified = verification: { $safe ->
    [true] SAFE
   *[other] NOT SAFE
} ({ $states } states), { $permissive ->
    [true] permissive
   *[other] NOT permissive
}
say-verified-parts = verification of { $parts } components: { $verdict ->
    [safe] SAFE
    [unproved] no hazard found, some components NOT PROVED
   *[other] NOT SAFE
}
say-no-replay-of-parts = this plant is verified per component: its traces are in `vigie verify`, not replayed on the synoptic
say-verify-failed = verification failed: { $error }
say-no-verification = no verification result to replay
say-no-counterexample = no counterexample: the set is safe on the model
say-counterexample-unwritable = cannot write the counterexample: { $error }
say-replaying = replaying the counterexample ({ $kind }) with the filter enforcing
say-counterexample-unreadable = counterexample: { $error }
fix-cannot-run = cannot re-run: { $error }
fix-nothing-delivered = not fixed: no trip but no box was delivered in the re-run (program { $version })
fix-correct = correct fix: no trip and no hazard in { $s } s, { $delivered } boxes delivered (program { $version })
fix-not-fixed = not fixed: the re-run has trips [{ $trips }] and hazards [{ $hazards }] (program { $version })

say-fault-injected = fault injected: { $what }
say-fault-refused = fault refused ({ $what }): { $error }

say-refused = Refused: { $what } needs the { $roles } role ({ $role } now): log in
perm-EditProgram = editing the program
perm-ChangeFilterMode = changing the filter's mode
perm-BypassConstraint = bypassing a safety constraint
perm-Train = loading exercises and injecting faults
role-operator = operator
role-maintenance = maintenance
role-trainer = trainer
role-administrator = administrator

say-alarms-printed = { $n } alarms laid out for printing in { $path }
say-print-open-failed = { $path } is written; it could not be opened to print ({ $error }): open it in a browser
print-title = Vigie: alarm history
print-plant = Plant: { $name }
print-run = Run: { $title }
print-printed = Printed { $time }
print-filter = Filter: { $filter }
print-search = text “{ $text }”
print-no-search = any text
print-col-raised = Raised
print-col-priority = Priority
print-col-kind = Kind
print-col-state = State
print-col-message = Alarm
print-col-cleared = Cleared
print-col-ack = Acknowledged
print-col-shelved = Shelved until
history-print-hover = The history as filtered, laid out for paper (HTML), then opened in the browser to print
history-print = Print…

## Training
training-title = Training
training-verify-fix = Verify fix
training-verify-fix-hover = Re-run the scenario with the edited program (Maintenance)
training-edit-program = Edit program
training-errors = Control-error library
training-load = Load { $id }
training-faults = Fault library
training-no-faults = No faults.ron in the plant folder.
training-inject = Inject
training-exercise = Exercise { $id }
training-exercise-how = The filter stopped the plant. Find the error with the explanation levels (start with the current state, ask for more as you need), correct it in Maintenance, then Verify fix.
training-show-answer = Show the answer
training-show-answer-hover = End the exercise without a correct fix: the debrief shows the mistake and its fix (recorded as given up)
training-faults-in-force = Faults in force on the simulator: { $n }
training-repair = Repair the plant
training-repair-hover = The technician's repair on the simulator: every fault ends now and the diagnosers are reset; then Reset the filter
debrief-title = Debrief: exercise { $id }
debrief-mistake = The mistake: { $text }
debrief-fix = The correct fix (exercise → reference program):
debrief-levels = Levels consulted: { $levels }
debrief-fixed = Fixed after { $attempts } fix checks, { $s } s after the stop.
debrief-given-up = Answer shown after { $attempts } fix checks, without a correct fix.
history-training-title = Training history of { $user }
history-training-anonymous = Training history (not logged in)
history-training-fixed = solved
history-training-given-up = given up
history-training-attempts = { $n } attempts
history-training-levels = levels { $levels }
history-training-none = No finished exercise yet.
history-training-unreadable = unreadable line of training.csv, kept as written: { $line }
say-no-exercise = no exercise loaded: load one from the control-error library
say-exercise-fixed = exercise { $id } fixed: see the debrief
say-exercise-given-up = exercise { $id } ended, answer shown: see the debrief
say-history-unwritable = the training history could not be written: { $error }
training-plant-exercises = Plant-fault exercises
training-plant-exercise-how = A component of the plant failed and the plant stopped. Find which one with the explanation levels (start with the current state, ask for more as you need), name it below, then repair the plant.
training-faulty-component = Faulty component:
training-pick-component = choose a sensor or an actuator
training-submit-diagnosis = Submit diagnosis
training-submit-diagnosis-hover = Name this component as the faulty one: right ends the exercise with the debrief, wrong counts an attempt
training-diagnosis-wrong = { $component } is not the faulty component.
debrief-fault = What failed: { $text }
debrief-answer = The faulty component: { $answer }
debrief-named = Your diagnoses: { $named }
debrief-found = Found after { $attempts } attempts, { $s } s after the stop.
debrief-not-found = Answer shown after { $attempts } attempts, the component not found.
debrief-found-before-stop = Found after { $attempts } attempts, before the plant stopped.
score-found = Found.
debrief-repair = The fault is still in force: Repair the plant, then Reset (Re-initialise… if the reset is refused) and Start.
score-found-in = Found, in { $s } s.
score-not-found = Not found yet.
say-diagnosis-right = { $component } is the faulty component: see the debrief
say-diagnosis-wrong = { $component } is not the faulty component
say-no-plant-exercise = no plant-fault exercise loaded: load one from the plant-fault exercises
say-no-such-exercise = no exercise { $id } in exercises.ron
# The run's title (status line); a scenario file has its own in the plant folder
# (`scenario-<file stem>`), else its `name`.
scenario-reference = Reference program
scenario-training = Training: { $id }
# A fault of the library, built from its kind (in English the console shows the name
# faults.ron gives it).
fault-stuck-at-0 = { $signal } stuck at 0{ $description }
fault-stuck-at-1 = { $signal } stuck at 1{ $description }
fault-spurious-rise = { $signal }: spurious pulse of { $ms } ms{ $description }
fault-spurious-fall = { $signal }: dropout of { $ms } ms{ $description }
fault-actuator-off = { $signal } stuck OFF{ $description }
fault-actuator-on = { $signal } stuck ON (welded contactor){ $description }
fault-stuck-at-position = { $component } stuck at { $position }
fault-slowed = { $signal } slowed to { $percent } %{ $description }
fault-blocked = { $component } blocked
fault-component-slowed = { $component } slowed to { $percent } %

## Maintenance
maint-program = Control program: { $name }, version { $version }
maint-program-exercise = Control program: exercise { $id } (a variant of « { $name } »), version { $version }
maint-edit-condition = Receptivity { $id }
maint-edit-actions = Actions of { $id }
maint-edit-equation = Equation { $id }
fix-check-title = Last fix check
fix-check-ran = Ran { $name }, version { $version }, on « { $scenario } »
fix-check-not-compiled = not compiled
fix-check-changes = Changed from the running program: { $changes }
fix-check-no-change = nothing (the running program itself)
maint-view-grafcet = GRAFCET
maint-view-ladder = Ladder
maint-view-text = Text
maint-no-equations = This program has no output equations.
grafcet-step = Step
grafcet-transition = Transition
grafcet-suspect = suspect
ladder-rung = Rung { $target }, { $state }
ladder-on = coil ON
ladder-off = coil OFF
expl-show-in-program = → { $element } in the program
maint-recompile = Recompile
maint-restart = Restart with edit
maint-discard = Discard edits
maint-verify-fix-hover = Re-run the scenario headless with the edit
maint-export-plcopen = Export PLCopen XML
maint-export-plcopen-as = Save PLCopen XML as…
maint-export-plcopen-hover = Write the program on screen as PLCopen XML, for the PLC's own tool (CODESYS, TwinCAT, Beremiz, OpenPLC Editor); Export writes it under the data folder
maint-chart = Chart { $name }
maint-active = active
maint-equations = Equations

## Chronogram
chrono-observers = Observers
chrono-aux = Auxiliaries (diagnosers, plausibility)
chrono-zoom-hover = Ctrl + mouse wheel over the chronogram zooms the time window
chrono-title = Chronogram
chrono-replay = Replay
chrono-live = Live
chrono-signals = Signals

## Diagnosers
diag-doubt-monitor = { $comp } in doubt between { $faults } ({ $p }, a drive, may be at fault; monitor: reported, not stopped)
diag-doubt-stop = Stopped on the safe side: { $comp } in doubt between { $faults } ({ $p }, a drive, may be at fault). Check the plant, then reset the diagnosers
diag-no-estimate = { $s } at fault (certain): no estimate in its model, { $s } is still read
diag-actuator-stop = Actuator partition { $p } at fault: the whole system is stopped
diag-actuator-monitor = Actuator partition { $p } at fault (monitor: reported, not stopped)
diag-estimated = { $s } estimated from time intervals ({ $hat }) — degraded mode
diag-sensor-monitor = { $s } at fault: the filter reads { $hat } (monitor: the PLC still reads { $s })
diag-partition = Partition { $p } at fault
diag-question = Question: { $question }
diag-item-there = Yes, an item is there ({ $sensor })
diag-no-item = No item there ({ $sensor })
diag-answer = Operator's answer: { $conclusion }
diag-reset = Reset diagnosers (after repair)
diag-reset-hover = The faulty sensor or actuator was repaired: clear the fault flags, read the sensors again and end the stop. A fault still present is diagnosed again.
diag-table = Diagnosers ({ $n } certain diagnoses)
diag-table-doubts = Diagnosers ({ $n } certain diagnoses, { $doubts } stops on the safe side)
diag-component = component
diag-estimate = state estimate
diag-decisions = decisions

## Training score
score-summary = Levels consulted: { $levels }. Attempts: { $attempts }. { $result }
score-none = none
score-fixed-in = Fixed, located in { $s } s.
score-fixed = Fixed.
score-not-fixed = Not fixed yet.

## Constraint set verification
verif-title = Constraint set verification
verif-run = Verify constraints
verif-run-hover = Explore the abstract model of the plant with any control and the filter in the loop: a turntable cell whole (at most 2 boxes: hazards, deliveries, invariants), any other plant one component at a time. Necessity of each constraint: `vigie verify --necessity`
verif-exploring = exploring… { $s } s
verif-not-yet = Not verified yet.
verif-states = { $states } reachable states, { $transitions } transitions ({ $s } s)
verif-safe = Safety: proved, no hazard reachable
verif-violated = Safety: VIOLATED, { $kind } reachable in { $n } steps
verif-hazard-kind = { $kind } ({ $n } steps)
verif-hazards = Hazards reachable: { $kinds }
verif-replay = Replay counterexample
verif-replay-hover = Play the shortest hazard trace on the synoptic, filter enforcing
verif-no-fallback = Some reachable context has no fallback vector
verif-left = left
verif-right = right
verif-no-delivery = Permissiveness { $side }: NO delivery reachable
verif-delivery-always = Permissiveness { $side }: delivery in { $n } steps, from every reachable state
verif-delivery-some = Permissiveness { $side }: delivery in { $n } steps; some states can no longer deliver
verif-invariants = Invariants
verif-proved = proved
verif-refuted = REFUTED
verif-parts = { $parts } components verified one at a time, each with the inputs it does not write free ({ $s } s)
verif-parts-verdict = { $verdict ->
    [safe] Safety: proved for every modelled component
    [unproved] Safety: no hazard found, but some components were not verified to the end
   *[other] Safety: VIOLATED on some component
}
verif-part-safe = safe with the filter
verif-part-violated = VIOLATED with the filter: { $hazards }
verif-part-truncated = NOT PROVED: the search stopped at its limit
verif-part-skipped = NOT VERIFIED: { $why }
verif-part-environment = by the environment alone: { $hazards }
verif-part-unguarded = no constraint
verif-part-guarded = Guarded by { $by }
verif-not-modelled = Not modelled (detectors, links): { $names }
verif-assumptions = Assumptions of the model
verif-sub-end-stop = end stop at { $end }
verif-sub-declared = danger `{ $id }`
verif-sub-collision = collision at the entry
verif-sub-dropped = item fallen off the end
verif-necessity-hint = Necessity of each constraint: `vigie verify --necessity` (one exploration per constraint).
verif-necessity = Necessity of each constraint
verif-necessary = necessary: without it { $hazard }
verif-redundant = redundant on this model

## Live link toolbar
link-gateway = LIVE GATEWAY
link-monitor = LIVE MONITOR
link-reset-hover = Operator reset of the gateway's safety filter
link-normal = Normal

## Words
word-or = or

## Synoptic tags
syn-held-on = held ON
syn-forced-off = forced OFF
syn-stays-on = stays ON
syn-stays-off = stays OFF
syn-suspect = suspect
syn-expected-on = expected ON
syn-expected-off = expected OFF
syn-inferred-box = inferred box
syn-estimated = estimated
syn-no-address = no fieldbus address
syn-other-signals = Other signals
syn-switch-closed = closed
syn-switch-open = open
syn-switch-moving = operating

## Texts built from the plant's data (French only: English is the core's record)
words-constraint-violated = constraint { $id } violated
words-safety-violation = Safety violation, plant not stopped (monitor mode: the filter only reports): { $why }
words-safety-stop = Safety stop: { $why }
words-diagnoser-stop = the diagnosers stop the plant: { $partition } at fault
words-held-on = . Held ON: { $list }
words-stopped = . Stopped: { $list }
words-not-tripped = the filter has not tripped
words-still-violated = reset refused: { $constraints } still violated by the commanded outputs
words-with-observers = {" "}(with { $observers } = 1)
words-list-sep = {"; "}
# Where an item was damaged, from the plant's parts (`part-<id>` in the plant folder).
place-edge = edge of the { $part }
place-against = { $part } (against item { $other_item })
place-end = end of the { $part }
place-start = start of the { $part }
place-between = between the { $part } and the { $other }
place-component = { $part }

## Status line
status-reinit-emptied = Re-initialised: the plant emptied, the program at its initial steps; press Start
status-reinit-in-place = Re-initialised with the items in place, the program at its initial steps; press Start
status-manual-on = Manual mode: every command is checked by the safety filter
status-manual-off = Automatic mode: the program restarted from its initial steps; press Start
status-by-hand-on = { $id } ON by hand
status-by-hand-off = { $id } OFF by hand
status-bypassed = { $constraint } bypassed for { $minutes } min: the banner stays while it lasts
status-enforced-again = { $id } enforced again
status-start-pressed = Start pressed
status-stop-pressed = Stop pressed
status-reset-done = Reset: the filter releases the plant
status-diagnosers-reset = Diagnosers reset: the sensors are read again
status-reset-refused = Reset: { $reason }. Still refused? Check the plant, then Re-initialise…
words-request-on = { $id } ON
words-request-off = { $id } OFF
words-request-off-meaning = { $id } OFF ({ $meaning })
words-request-refused = { $what } refused: { $why }
words-with = , with { $values }
status-export-cancelled = Export cancelled (no save dialog on this desktop? The Export button beside it writes under the data folder)

## Alarms of earlier runs (the historian)
past-title = Alarms of earlier runs (historian)
past-count = { $n } alarms in the last { $days } days, every session of this data folder (console and gateway), newest first, as recorded

## Alarm kinds (history filter)
kind-safety-filter-trip = safety filter trip
kind-diagnosis = diagnosis
kind-task-monitor = task monitor
kind-live-link = live link
kind-specification-error = specification error
kind-hazard = hazard
kind-implausible-sensor = implausible sensor
kind-program-divergence = program divergence
syn-elevator-left = Left elevator
syn-elevator-right = Right elevator

## Live-link panel
linkp-title = Live link
linkp-mode-gateway = Mode: gateway (filter enforced between PLC and plant)
linkp-mode-monitor = Mode: monitor (read-only, filter reports)
linkp-stopped-error = Link: stopped ({ $error })
linkp-stopped = Link: stopped
linkp-connected = Link: connected to { $peer }
linkp-connecting = Link: connecting to { $peer }
linkp-reconnecting = Link: reconnecting to { $peer } (attempt { $attempt }, next in { $ms } ms)
linkp-last-poll = Last poll: { $ms } ms ago
linkp-never-polled = Last poll: never
linkp-no-stale = Stale inputs: none
linkp-stale = Stale inputs: { $inputs }
linkp-cycles = Cycles: { $n }
linkp-protocol = Protocol: { $protocol }
linkp-plc-protocol = PLC side: { $protocol }
linkp-exceptions = Exceptions: { $n } (transport errors { $errors }, connections { $connections })
linkp-plc-server = PLC server: { $address }
linkp-plc-heard = PLC: heard
linkp-plc-silent = PLC: silent
linkp-plc-refused = PLC requests refused: { $n }
linkp-safe-outputs = Safe outputs: { $reason }
linkp-dropped = { $n } cycles not shown (the console fell behind)
linkp-status = { $poll } · { $stale } · { $cycles } cycles · { $exceptions } exceptions

## Incident report
report-nobody = nobody logged in
report-date = Exported: { $date }
report-user = User: { $user } (role { $role })
report-plant = Plant: { $name } (folder `{ $folder }`)
report-program = Control program: { $name }, version `{ $version }`
report-program-exercise = Control program: exercise { $id } (a variant of « { $name } »), version `{ $version }`
report-run = Run: { $title }
report-filter = Filter mode: { $mode }
report-vigie = Vigie { $version }
report-chronogram = Chronogram of the trip window
report-chronogram-screen = The chronogram as it was on screen (the rows and the window the user had chosen):
report-chronogram-legend = Black: sensors read · blue: outputs applied · amber: the filter applied another value than the command · violet: observers · red: the stop
report-title = Incident report
report-trip = Trip at **{ $time_ms } ms** (cycle { $cycle })
report-constraint = Constraint **{ $id }**: `{ $source }` — { $notation }
report-fallback = Fallback: { $outputs }
report-trace = Trace before the trip (changes)
report-time-ms = time ms
report-changes = changes
syn-predicted = predicted: %kind% box %box%
syn-hazard-sheared = Sheared
syn-hazard-dropped = Dropped
syn-hazard-collision = Collision
syn-hazard-pushedagainststopped = PushedAgainstStopped
syn-hazard-endstop = driven into its end stop
syn-hazard-opposeddrives = driven both ways at once
syn-hazard-declared = dangerous state
syn-hazard-overflow = overflow
syn-hazard-dryrun = pump running dry
syn-predicted-component = predicted: %kind%
