# Console Vigie, français. Chaque message a son jumeau dans en.ftl (un test le vérifie).
# Les textes d'une installation (descriptions des signaux) vont dans le dossier de
# l'installation, i18n/<langue>.ftl.

## Choix de la langue
lang-switch-hover = Langue de la console

## Barre d'outils
mode-production = Production
mode-maintenance = Maintenance
mode-training = Formation
mode-maintenance-needs-role = Modifier le programme demande le rôle maintenance : connectez-vous
sim-pause = Pause
sim-run = Marche
sim-step = Pas
sim-step-hover = Un cycle automate
sim-speed = Vitesse
plant-start = Départ cycle
plant-start-hover = Bouton DÉPART CYCLE de la machine
plant-stop = Arrêt
plant-stop-hover = Bouton ARRÊT de la machine

## État d'un coup d'œil
state-tripped = ARRÊT SÉCURITÉ
state-stopped = ARRÊTÉE
state-manual = MANUEL
state-degraded = DÉGRADÉ
state-idle = AU REPOS
state-running = EN PRODUCTION
state-tripped-hover = Le filtre de sécurité maintient les sorties dans leur état sûr
state-stopped-hover = Les diagnostiqueurs ont arrêté la machine : vérifiez-la, puis réarmez-les
state-manual-hover = L'opérateur pilote les sorties ; chaque commande est vérifiée
state-degraded-hover = Un capteur est lu par son estimation ou tenu pour suspect
state-idle-hover = Le programme est au repos : appuyez sur Départ cycle pour produire
state-running-hover = Le programme s'exécute
state-paused = SIMULATION EN PAUSE
state-unacknowledged = { $n ->
    [one] { $n } non acquittée
   *[other] { $n } non acquittées
}

## Panneau central
tab-synoptic = Synoptique
tab-trends = Courbes
tab-trends-hover = L'historique de n'importe quel signal, sur des minutes ou des jours
synoptic-whole-plant = Toute l'installation
synoptic-area-hover = Une zone de l'installation à la fois, lisible ; ⚠ signale la zone de l'arrêt

## Courbes
trends-1-min = 1 min
trends-10-min = 10 min
trends-1-h = 1 h
trends-8-h = 8 h
trends-1-day = 1 jour
trends-7-days = 7 jours
trends-range = Durée
trends-add = Ajouter un signal…
trends-full = { $n } signaux au plus
trends-filter = Filtrer
trends-remove-hover = Retirer { $signal } des courbes
trends-export = Exporter en CSV…
trends-export-hover = Les changements de ces signaux sur la durée, dans un fichier de votre choix
trends-no-history = Pas d'historique : la console tourne sans dossier de données (le journal n'est qu'en mémoire).
trends-empty = Ajoutez un signal pour voir son historique.
trends-legend = Chaque ligne est un signal, haut à 1 ; une barre pleine est un signal qui a changé plus vite que l'écran ne peut le montrer (zoomez). « .cmd » est la sortie commandée par le programme, sans lui la sortie appliquée.
trends-now = maintenant

## Installation non protégée
unprotected-banner = NON PROTÉGÉE : aucune contrainte de sécurité, le filtre laisse passer toutes les commandes

## Barre d'outils : mode manuel, réarmement, réinitialisation, connexion
manual-leave = Quitter le manuel
manual-leave-hover = Retour au programme, relancé depuis ses étapes initiales
manual-enter = Mode manuel…
manual-enter-hover = Piloter les actionneurs à la main, chaque commande passant par le filtre
manual-enter-disabled-hover = Impossible tant que le filtre maintient la machine, ou sur une liaison en direct
reset = Réarmer
reset-hover = Réarmement du filtre de sécurité par l'opérateur
reinit = Réinitialiser…
reinit-hover = Quand le réarmement est refusé parce que le programme ou un observateur croit encore ce qu'un transitoire lui a fait croire : après une vérification de la machine (vidée, ou chaque pièce là où un capteur la montre), le programme revient à ses étapes initiales, les capteurs sont pris tels qu'ils sont lus
reinit-disabled-hover = Seulement après un arrêt sécurité, sur l'émulateur (sur une liaison en direct, le programme de l'automate se réinitialise sur l'automate)
logout = Se déconnecter
login = Se connecter…
login-hover = Rôle opérateur jusqu'à une connexion maintenance, formateur ou administrateur
plant-picker-hover = Ouvrir un autre dossier d'installation (son programme de référence ; la session recommence)

## Dialogues
cancel = Annuler
login-title = Connexion à la console
login-no-accounts = Aucun compte dans le dossier de données : un administrateur les crée avec `vigie user add NOM --role maintenance` (le mot de passe sur l'entrée standard).
login-user = Utilisateur
login-password = Mot de passe
login-submit = Se connecter
manual-confirm-title = Piloter la machine à la main ?
manual-confirm-text = Le programme n'est plus exécuté et les sorties restent en l'état. Vous mettez alors chaque actionneur en marche ou à l'arrêt, ou le pilotez par à-coups tant que le bouton est maintenu. Chaque commande est d'abord vérifiée par rapport aux contraintes de sécurité : celle qui violerait une contrainte est refusée avec sa raison et n'atteint jamais la machine. Quitter le mode manuel relance le programme depuis ses étapes initiales.
manual-confirm-enter = Passer en mode manuel
reinit-title = Réinitialiser après une vérification de la machine
reinit-text = Le programme revient à ses étapes initiales, comme en début de poste, les capteurs sont pris tels qu'ils sont lus et l'arrêt sécurité prend fin. Le filtre vérifie les commandes suivantes comme les autres, et les diagnostiqueurs ne décident rien avec certitude tant que chaque modèle n'est pas revenu à son état initial.
reinit-empty-first = Videz d'abord la machine : retirez chaque pièce à la main, y compris celles tombées (les étapes initiales n'attendent aucune pièce à mi-chemin). Chaque observateur redémarre alors à vide.
reinit-emulator = Sur l'émulateur, les pièces émulées sont retirées pour vous.
reinit-leave-in-place = Ou laissez les pièces en place, chacune là où un capteur la montre, aucune entre les capteurs : un observateur n'est alors remis à zéro que là où les capteurs ne laissent pas de place à sa pièce, et le programme peut s'arrêter à nouveau sur une pièce qu'il n'attend pas.
reinit-emptied = Machine vidée : réinitialiser
reinit-items-left = Pièces laissées en place : réinitialiser

## Dérivation
bypass-banner = DÉRIVATION : { $id }{ $what } n'est pas appliquée jusqu'à { $until } (reste { $min } min { $s } s), par { $by } : { $reason }
bypass-end = Fin de la dérivation de { $id }
bypass-title = Mettre une contrainte en dérivation
bypass-needs-role = Mettre une contrainte de sécurité en dérivation demande le rôle maintenance : connectez-vous.
bypass-reason = Motif de la dérivation
bypass-now = Mettre en dérivation
bypass-now-hover = Le filtre cesse d'appliquer cette contrainte jusqu'à la fin du délai

## Mode manuel
manual-title = Mode manuel
manual-note = Chaque commande est vérifiée par rapport aux contraintes de sécurité ; une commande refusée n'atteint jamais la machine.
manual-on = MARCHE
manual-off = ARRÊT
manual-set-on = { $id } MARCHE
manual-set-off = { $id } ARRÊT
manual-jog = À-coups { $id }
manual-jog-hover = MARCHE tant que le bouton est maintenu

## Ligne d'état
status-removed = , { $n ->
    [one] { $n } retirée
   *[other] { $n } retirées
}
status-boxes = { $scenario } — caisses : { $created } créées, { $delivered } livrées, { $damaged } endommagées{ $removed }
status-actions = { $scenario } — actions élémentaires : { $done } terminées, { $faults } défauts
status-items = pièces : { $placed } posées, { $out } sorties (livrées ou prises)

## Bandeaux du synoptique
banner-level = Niveau { $level } — arrêt sécurité { $ids } à { $time }
banner-replay = RELECTURE à { $time } (en direct : { $now })
banner-trip = ARRÊT SÉCURITÉ { $ids } — le filtre de sécurité maintient la machine

## Que faire après un arrêt sécurité
next-title = Que faire maintenant (arrêt à { $time })
next-why = 1. Pourquoi : { $text }.
next-check = 2. À vérifier sur la machine : { $where }.
next-reset-possible = 3. Le réarmement est possible : appuyez sur Réarmer, puis sur Départ cycle si le programme était arrêté.
next-reset-refused = 3. Le réarmement est refusé pour l'instant ({ $reason }). Une fois la cause disparue (la pièce a avancé, le capteur lit juste), appuyez sur Réarmer ; s'il reste refusé, vérifiez la machine et Réinitialiser…

## Explication
level-0 = 0 État actuel
level-1 = 1 Projection
level-2 = 2 Avant l'arrêt
level-3 = 3 Avancé
level-4 = 4 Hypothèse
expl-title = Explication
expl-no-trip = Aucun arrêt sécurité : la machine fonctionne dans ses contraintes de sécurité.
expl-action-stop = Arrêt par la surveillance des actions élémentaires (aucune contrainte déclenchée) : { $why }. Le détail de l'alarme dit quoi vérifier ; réparer, puis Réarmer : le programme repart de ses étapes initiales.
expl-violation-at = Violation à { $time } (mode surveillance : la machine n'a pas été arrêtée)
expl-trip-at = Arrêt sécurité à { $time }
expl-as-written = tel qu'écrit : { $id } = { $notation }
expl-level = Niveau { $level }
expl-nothing = Rien à signaler à ce niveau.
expl-choose-level = Choisissez un niveau pour l'afficher sur le synoptique.
expl-save-report-as = Enregistrer le rapport sous…
expl-report-folder = Dossier des rapports
expl-export-report = Exporter le rapport d'incident

## Alarmes
prio-urgent = URGENTE
prio-high = HAUTE
prio-medium = MOYENNE
alarms-title = Alarmes
alarms-show-shelved = afficher les masquées
alarms-ack-all = Tout acquitter ({ $n })
alarms-none = Aucune alarme active.
alarms-previous = ◀ Précédente
alarms-page = Page { $page } sur { $pages }
alarms-next = Suivante ▶
alarms-ack-page = Acquitter la page
alarm-unack = NON ACQ.
alarm-ack = ACQ.
alarm-cleared-unack = DISPARUE-NON ACQ.
alarm-normal = NORMALE
alarm-first-out = PREMIÈRE ALARME
alarm-shelved-until = (masquée jusqu'à { $until } : { $reason })
alarm-detail = Détail
alarm-acknowledged-at = acquittée à { $time } : { $note }
alarm-note-hint = commentaire
alarm-acknowledge = Acquitter n° { $id }
alarm-unshelve = Démasquer n° { $id }
alarm-shelve = Masquer n° { $id }…
alarm-shelve-safety = Une alarme de sécurité (arrêt sécurité, danger, erreur de spécification, liaison en direct) n'est jamais masquée
shelve-reason = Motif
shelve-reason-hint = pourquoi (obligatoire)
shelve-now = Masquer n° { $id } maintenant
shelve-needs-reason = Masquer une alarme demande un motif

## Performance des alarmes
kpi-rate = Fréquence : { $last } sur les 10 dernières min (moyenne { $average }, pic { $peak })
kpi-flood = AVALANCHE D'ALARMES
kpi-title = Performance des alarmes
kpi-summary = { $total ->
    [one] { $total } alarme
   *[other] { $total } alarmes
} en { $intervals ->
    [one] { $intervals } intervalle
   *[other] { $intervals } intervalles
} de 10 min ; { $floods } en avalanche (plus de { $limit } alarmes)
kpi-chattering = Alarmes battantes (3 fois ou plus en une minute) : { $sources }

## Historique des alarmes
history-title = Historique des alarmes ({ $n })
history-search = Rechercher
history-every-kind = tous types
history-every-priority = toutes priorités
history-count = { $n } sur { $total }
history-export = Exporter les alarmes en CSV
history-save-as = Enregistrer les alarmes sous…
history-cleared = , disparue à { $time }
history-ack = , acquittée à { $time }
history-more = … { $n } de plus : affinez la recherche ou exportez

## Journal
journal-title = Journal
journal-written-to = écrit dans { $path }
journal-csv-file = Fichier CSV
journal-export-csv = Exporter en CSV
journal-export-csv-hover = Écrit dans le dossier de données
journal-save-as = Enregistrer le journal sous…
journal-exports-under = Les exports vont dans { $path }

## Ce que la console dit et journalise (le journal garde le texte anglais et l'id du
## message, et montre une entrée dans la langue affichée)
say-session = console ouverte sur { $scenario }
say-login = { $user } connecté ({ $role })
login-wrong = utilisateur inconnu ou mot de passe erroné
say-login-locked = Connexion bloquée pendant { $s } s après { $n } échecs
say-login-refused = Connexion refusée : { $error }
say-logout = { $user } déconnecté
say-program-exported = programme { $name } (version { $version }) exporté en PLCopen XML dans { $path }
say-program-export-refused = le programme affiché ne compile pas ({ $problems } problèmes) : rien n'est exporté
say-program-export-failed = impossible d'exporter le programme dans { $path } : { $error }
say-logged-out = Déconnecté : rôle opérateur
say-mode = mode { $mode ->
    [Production] Production
    [Maintenance] Maintenance
    [Training] Formation
   *[other] { $mode }
}
say-ack = alarme { $id } acquittée : { $note }
say-ack-refused = acquittement refusé : { $error }
say-ack-all = { $n } alarme(s) acquittée(s)
say-ack-together = alarmes { $list } acquittées ensemble : { $note }
say-shelve = alarme { $id } masquée pendant { $minutes } min : { $reason }
say-shelve-refused = Masquage refusé : { $error }
say-unshelve = alarme { $id } démasquée
say-unshelve-refused = démasquage refusé : { $error }
say-language = langue { $lang }
say-restart = redémarrage : { $scenario }
say-restarted = redémarré
say-restart-failed = redémarrage impossible : { $error }
say-compiled = programme compilé
say-compile-failed = la compilation a échoué
say-nothing-to-verify = rien à vérifier : la modification ne compile pas
say-no-trip = aucun arrêt à rapporter
say-report-written = rapport écrit dans { $path } ; capture des niveaux…
say-report = rapport d'incident { $path }
say-report-failed = rapport impossible : { $error }
say-png-failed = PNG impossible : { $error }
say-report-complete = rapport d'incident complet dans { $path }
say-report-no-png = rapport Markdown dans { $path } ; capture PNG indisponible ici
say-alarms-exported = { $n } alarmes exportées dans { $path }
say-alarms-export-failed = l'export des alarmes dans { $path } a échoué : { $error }
say-trend-exported = { $n } changements exportés dans { $path }
say-trend-export-failed = l'export des courbes dans { $path } a échoué : { $error }

say-verifying = vérification du jeu de contraintes…
say-verify-cannot-start = impossible de lancer la vérification : { $error }
say-verified = vérification : { $safe ->
    [true] SÛR
   *[other] PAS SÛR
} ({ $states } états), { $permissive ->
    [true] permissif
   *[other] PAS permissif
}
say-verified-parts = vérification de { $parts } composants : { $verdict ->
    [safe] SÛR
    [unproved] aucun danger trouvé, certains composants NON PROUVÉS
   *[other] PAS SÛR
}
say-no-replay-of-parts = cette machine est vérifiée composant par composant : ses traces sont dans `vigie verify`, elles ne se rejouent pas sur le synoptique
say-verify-failed = la vérification a échoué : { $error }
say-no-verification = aucun résultat de vérification à rejouer
say-no-counterexample = pas de contre-exemple : le jeu est sûr sur le modèle
say-counterexample-unwritable = impossible d'écrire le contre-exemple : { $error }
say-replaying = rejeu du contre-exemple ({ $kind }) avec le filtre actif
say-counterexample-unreadable = contre-exemple : { $error }
fix-cannot-run = impossible de rejouer : { $error }
fix-nothing-delivered = pas corrigé : aucun arrêt, mais aucune caisse livrée pendant le rejeu (programme { $version })
fix-correct = correction juste : aucun arrêt ni dommage en { $s } s, { $delivered } caisses livrées (programme { $version })
fix-not-fixed = pas corrigé : le rejeu a des arrêts [{ $trips }] et des dommages [{ $hazards }] (programme { $version })

say-fault-injected = défaut injecté : { $what }
say-fault-refused = défaut refusé ({ $what }) : { $error }

say-refused = Refusé : { $what } demande le rôle { $roles } (rôle actuel : { $role }) ; connectez-vous
perm-EditProgram = modifier le programme
perm-ChangeFilterMode = changer le mode du filtre
perm-BypassConstraint = dériver une contrainte de sécurité
perm-Train = charger des exercices et injecter des défauts
role-operator = opérateur
role-maintenance = maintenance
role-trainer = formateur
role-administrator = administrateur

say-alarms-printed = { $n } alarmes mises en page pour l'impression dans { $path }
say-print-open-failed = { $path } est écrit ; impossible de l'ouvrir pour l'imprimer ({ $error }) : ouvrez-le dans un navigateur
print-title = Vigie : historique des alarmes
print-plant = Installation : { $name }
print-run = Marche : { $title }
print-printed = Imprimé le { $time }
print-filter = Filtre : { $filter }
print-search = texte « { $text } »
print-no-search = tout texte
print-col-raised = Apparue
print-col-priority = Priorité
print-col-kind = Nature
print-col-state = État
print-col-message = Alarme
print-col-cleared = Disparue
print-col-ack = Acquittée
print-col-shelved = Masquée jusqu'à
history-print-hover = L'historique filtré, mis en page pour le papier (HTML), puis ouvert dans le navigateur pour l'imprimer
history-print = Imprimer…

## Formation
training-title = Formation
training-verify-fix = Vérifier la correction
training-verify-fix-hover = Rejouer le scénario avec le programme modifié (Maintenance)
training-edit-program = Modifier le programme
training-errors = Bibliothèque d'erreurs de commande
training-load = Charger { $id }
training-faults = Bibliothèque de défauts
training-no-faults = Pas de faults.ron dans le dossier de l'installation.
training-inject = Injecter
training-exercise = Exercice { $id }
training-exercise-how = Le filtre a arrêté la machine. Trouvez l'erreur avec les niveaux d'explication (commencez par l'état courant, demandez-en plus selon vos besoins), corrigez-la en Maintenance, puis Vérifier la correction.
training-show-answer = Voir la réponse
training-show-answer-hover = Terminer l'exercice sans correction juste : le débriefing montre l'erreur et sa correction (enregistré comme abandon)
training-faults-in-force = Défauts en cours sur le simulateur : { $n }
training-repair = Réparer la machine
training-repair-hover = La réparation du technicien sur le simulateur : tous les défauts cessent et les diagnostiqueurs sont réinitialisés ; ensuite, Réarmer le filtre
debrief-title = Débriefing : exercice { $id }
debrief-mistake = L'erreur : { $text }
debrief-fix = La bonne correction (exercice → programme de référence) :
debrief-levels = Niveaux consultés : { $levels }
debrief-fixed = Corrigé après { $attempts } vérifications, { $s } s après l'arrêt.
debrief-given-up = Réponse affichée après { $attempts } vérifications, sans correction juste.
history-training-title = Historique de formation de { $user }
history-training-anonymous = Historique de formation (sans connexion)
history-training-fixed = résolu
history-training-given-up = abandon
history-training-attempts = { $n } tentatives
history-training-levels = niveaux { $levels }
history-training-none = Aucun exercice terminé pour l'instant.
history-training-unreadable = ligne illisible de training.csv, gardée telle quelle : { $line }
say-no-exercise = aucun exercice chargé : chargez-en un depuis la bibliothèque d'erreurs de commande
say-exercise-fixed = exercice { $id } corrigé : voir le débriefing
say-exercise-given-up = exercice { $id } terminé, réponse affichée : voir le débriefing
say-history-unwritable = l'historique de formation n'a pas pu être écrit : { $error }
training-plant-exercises = Exercices de défaut de la partie opérative
training-plant-exercise-how = Un composant de la machine est en défaut et la machine s'est arrêtée. Trouvez lequel avec les niveaux d'explication (commencez par l'état courant, demandez-en plus selon vos besoins), désignez-le ci-dessous, puis réparez la machine.
training-faulty-component = Composant en défaut :
training-pick-component = choisir un capteur ou un actionneur
training-submit-diagnosis = Valider le diagnostic
training-submit-diagnosis-hover = Désigner ce composant comme le composant en défaut : juste, l'exercice se termine par le débriefing ; faux, une tentative est comptée
training-diagnosis-wrong = { $component } n'est pas le composant en défaut.
debrief-fault = Ce qui a lâché : { $text }
debrief-answer = Le composant en défaut : { $answer }
debrief-named = Vos diagnostics : { $named }
debrief-found = Trouvé après { $attempts } tentatives, { $s } s après l'arrêt.
debrief-not-found = Réponse affichée après { $attempts } tentatives, composant non trouvé.
debrief-found-before-stop = Trouvé après { $attempts } tentatives, avant l'arrêt de la machine.
score-found = Trouvé.
debrief-repair = Le défaut est toujours présent : Réparer la machine, puis Réarmer (Réinitialiser… si le réarmement est refusé) et Marche.
score-found-in = Trouvé, en { $s } s.
score-not-found = Pas encore trouvé.
say-diagnosis-right = { $component } est le composant en défaut : voir le débriefing
say-diagnosis-wrong = { $component } n'est pas le composant en défaut
say-no-plant-exercise = aucun exercice de défaut chargé : chargez-en un depuis les exercices de défaut de la partie opérative
say-no-such-exercise = pas d'exercice { $id } dans exercises.ron
# Le titre de la marche (ligne d'état) ; un fichier de scénario a le sien dans le dossier
# de l'installation (`scenario-<nom du fichier>`).
scenario-reference = Programme de référence
scenario-training = Formation : { $id }
# Un défaut de la bibliothèque, construit à partir de sa nature (le nom de faults.ron est
# celui de l'auteur, en anglais).
fault-stuck-at-0 = { $signal } bloqué à 0{ $description }
fault-stuck-at-1 = { $signal } bloqué à 1{ $description }
fault-spurious-rise = { $signal } : impulsion parasite de { $ms } ms{ $description }
fault-spurious-fall = { $signal } : coupure de { $ms } ms{ $description }
fault-actuator-off = { $signal } bloqué À L'ARRÊT{ $description }
fault-actuator-on = { $signal } bloqué EN MARCHE (contacteur soudé){ $description }
fault-stuck-at-position = { $component } bloqué en { $position }
fault-slowed = { $signal } ralenti à { $percent } %{ $description }
fault-blocked = { $component } bloqué
fault-component-slowed = { $component } ralenti à { $percent } %

## Maintenance
maint-program = Programme : { $name }, version { $version }
maint-program-exercise = Programme : exercice { $id } (variante de « { $name } »), version { $version }
maint-edit-condition = Réceptivité { $id }
maint-edit-actions = Actions de { $id }
maint-edit-equation = Équation { $id }
fix-check-title = Dernière vérification de correction
fix-check-ran = Rejoué : { $name }, version { $version }, sur « { $scenario } »
fix-check-not-compiled = non compilé
fix-check-changes = Modifié par rapport au programme en cours : { $changes }
fix-check-no-change = rien (le programme en cours lui-même)
maint-view-grafcet = GRAFCET
maint-view-ladder = Ladder
maint-view-text = Texte
maint-no-equations = Ce programme n'a pas d'équations de sortie.
grafcet-step = Étape
grafcet-transition = Transition
grafcet-suspect = suspect
ladder-rung = Échelon { $target }, { $state }
ladder-on = bobine EN MARCHE
ladder-off = bobine À L'ARRÊT
expl-show-in-program = → { $element } dans le programme
maint-recompile = Recompiler
maint-restart = Redémarrer avec la modification
maint-discard = Abandonner les modifications
maint-verify-fix-hover = Rejouer le scénario sans affichage avec la modification
maint-export-plcopen = Exporter en PLCopen XML
maint-export-plcopen-as = Enregistrer en PLCopen XML sous…
maint-export-plcopen-hover = Écrire le programme affiché en PLCopen XML, pour l'outil de l'automate (CODESYS, TwinCAT, Beremiz, OpenPLC Editor) ; Exporter l'écrit dans le dossier de données
maint-chart = Grafcet { $name }
maint-active = active
maint-equations = Équations

## Chronogramme
chrono-observers = Observateurs
chrono-aux = Auxiliaires (diagnostiqueurs, plausibilité)
chrono-zoom-hover = Ctrl + molette sur le chronogramme : zoom de la fenêtre de temps
chrono-title = Chronogramme
chrono-replay = Relecture
chrono-live = Direct
chrono-signals = Signaux

## Diagnostiqueurs
diag-doubt-monitor = { $comp } en doute entre { $faults } ({ $p }, un entraînement, peut être en défaut ; surveillance : signalé, pas d'arrêt)
diag-doubt-stop = Arrêt du côté sûr : { $comp } en doute entre { $faults } ({ $p }, un entraînement, peut être en défaut). Vérifiez la machine, puis réarmez les diagnostiqueurs
diag-no-estimate = { $s } en défaut (certain) : pas d'estimation dans son modèle, { $s } est toujours lu
diag-actuator-stop = Partition actionneur { $p } en défaut : tout le système est arrêté
diag-actuator-monitor = Partition actionneur { $p } en défaut (surveillance : signalé, pas d'arrêt)
diag-estimated = { $s } estimé à partir des intervalles de temps ({ $hat }) — mode dégradé
diag-sensor-monitor = { $s } en défaut : le filtre lit { $hat } (surveillance : l'automate lit toujours { $s })
diag-partition = Partition { $p } en défaut
diag-question = Question : { $question }
diag-item-there = Oui, une pièce est là ({ $sensor })
diag-no-item = Pas de pièce ({ $sensor })
diag-answer = Réponse de l'opérateur : { $conclusion }
diag-reset = Réarmer les diagnostiqueurs (après réparation)
diag-reset-hover = Le capteur ou l'actionneur défaillant a été réparé : effacer les indicateurs de défaut, relire les capteurs et mettre fin à l'arrêt. Un défaut toujours présent est diagnostiqué à nouveau.
diag-table = Diagnostiqueurs ({ $n ->
    [one] { $n } diagnostic certain
   *[other] { $n } diagnostics certains
})
diag-table-doubts = Diagnostiqueurs ({ $n ->
    [one] { $n } diagnostic certain
   *[other] { $n } diagnostics certains
}, { $doubts ->
    [one] { $doubts } arrêt du côté sûr
   *[other] { $doubts } arrêts du côté sûr
})
diag-component = composant
diag-estimate = état estimé
diag-decisions = décisions

## Score de formation
score-summary = Niveaux consultés : { $levels }. Tentatives : { $attempts }. { $result }
score-none = aucun
score-fixed-in = Corrigé, erreur localisée en { $s } s.
score-fixed = Corrigé.
score-not-fixed = Pas encore corrigé.

## Vérification du jeu de contraintes
verif-title = Vérification du jeu de contraintes
verif-run = Vérifier les contraintes
verif-run-hover = Explorer le modèle abstrait de la machine avec toute commande et le filtre dans la boucle : une cellule à table tournante en entier (2 caisses au plus : dangers, livraisons, invariants), toute autre machine composant par composant. Nécessité de chaque contrainte : `vigie verify --necessity`
verif-exploring = exploration… { $s } s
verif-not-yet = Pas encore vérifié.
verif-states = { $states } états atteignables, { $transitions } transitions ({ $s } s)
verif-safe = Sécurité : prouvée, aucun danger atteignable
verif-violated = Sécurité : VIOLÉE, { $kind } atteignable en { $n } pas
verif-hazard-kind = { $kind } ({ $n } pas)
verif-hazards = Dangers atteignables : { $kinds }
verif-replay = Rejouer le contre-exemple
verif-replay-hover = Jouer sur le synoptique la plus courte trace menant à un danger, filtre actif
verif-no-fallback = Un contexte atteignable n'a pas de vecteur de repli
verif-left = à gauche
verif-right = à droite
verif-no-delivery = Permissivité { $side } : AUCUNE livraison atteignable
verif-delivery-always = Permissivité { $side } : livraison en { $n } pas, depuis tout état atteignable
verif-delivery-some = Permissivité { $side } : livraison en { $n } pas ; certains états ne peuvent plus livrer
verif-invariants = Invariants
verif-proved = prouvé
verif-refuted = RÉFUTÉ
verif-parts = { $parts } composants vérifiés un à un, chacun avec libres les entrées qu'il n'écrit pas ({ $s } s)
verif-parts-verdict = { $verdict ->
    [safe] Sécurité : prouvée pour chaque composant modélisé
    [unproved] Sécurité : aucun danger trouvé, mais certains composants n'ont pas été vérifiés jusqu'au bout
   *[other] Sécurité : VIOLÉE sur un composant
}
verif-part-safe = sûr avec le filtre
verif-part-violated = VIOLÉ avec le filtre : { $hazards }
verif-part-truncated = NON PROUVÉ : la recherche s'est arrêtée à sa limite
verif-part-skipped = NON VÉRIFIÉ : { $why }
verif-part-environment = par l'environnement seul : { $hazards }
verif-part-unguarded = aucune contrainte
verif-part-guarded = Gardé par { $by }
verif-not-modelled = Non modélisés (détecteurs, liaisons) : { $names }
verif-assumptions = Hypothèses du modèle
verif-sub-end-stop = butée en { $end }
verif-sub-declared = danger `{ $id }`
verif-sub-collision = collision à l'entrée
verif-sub-dropped = pièce tombée en bout
verif-necessity-hint = Nécessité de chaque contrainte : `vigie verify --necessity` (une exploration par contrainte).
verif-necessity = Nécessité de chaque contrainte
verif-necessary = nécessaire : sans elle { $hazard }
verif-redundant = redondante sur ce modèle

## Barre d'outils de la liaison en direct
link-gateway = PASSERELLE EN DIRECT
link-monitor = SURVEILLANCE EN DIRECT
link-reset-hover = Réarmement du filtre de sécurité de la passerelle par l'opérateur
link-normal = Normal

## Words
word-or = ou

## Étiquettes du synoptique
syn-held-on = maintenu EN MARCHE
syn-forced-off = forcé À L'ARRÊT
syn-stays-on = reste EN MARCHE
syn-stays-off = reste À L'ARRÊT
syn-suspect = suspect
syn-expected-on = attendu EN MARCHE
syn-expected-off = attendu À L'ARRÊT
syn-inferred-box = caisse déduite
syn-estimated = estimé
syn-no-address = pas d'adresse sur le bus
syn-other-signals = Autres signaux
syn-switch-closed = fermé
syn-switch-open = ouvert
syn-switch-moving = en manœuvre

## Textes construits à partir des données de l'installation
words-constraint-violated = contrainte { $id } violée
words-safety-violation = Violation de sécurité, machine non arrêtée (mode surveillance : le filtre signale seulement) : { $why }
words-safety-stop = Arrêt sécurité : { $why }
words-diagnoser-stop = les diagnostiqueurs arrêtent la machine : { $partition } en défaut
words-held-on = . Maintenus EN MARCHE : { $list }
words-stopped = . Arrêtés : { $list }
words-not-tripped = le filtre n'est pas déclenché
words-still-violated = réarmement refusé : { $constraints } encore violée(s) par les sorties commandées
words-with-observers = {" "}(avec { $observers } = 1)
words-list-sep = {" ; "}
# Le lieu d'un dommage, à partir des parties de l'installation (`part-<id>` dans le
# dossier de l'installation).
place-edge = { $part } (bord)
place-against = { $part }, contre la caisse { $other_item }
place-end = { $part } (extrémité aval)
place-start = { $part } (extrémité amont)
place-between = jonction { $part } / { $other }
place-component = { $part }

## Ligne d'état
status-reinit-emptied = Réinitialisée : la machine vidée, le programme à ses étapes initiales ; appuyez sur Départ cycle
status-reinit-in-place = Réinitialisée avec les pièces en place, le programme à ses étapes initiales ; appuyez sur Départ cycle
status-manual-on = Mode manuel : chaque commande est vérifiée par le filtre de sécurité
status-manual-off = Mode automatique : le programme repart de ses étapes initiales ; appuyez sur Départ cycle
status-by-hand-on = { $id } EN MARCHE à la main
status-by-hand-off = { $id } À L'ARRÊT à la main
status-bypassed = { $constraint } en dérivation pour { $minutes } min : le bandeau reste affiché tant qu'elle dure
status-enforced-again = { $id } de nouveau appliquée
status-start-pressed = Départ cycle appuyé
status-stop-pressed = Arrêt appuyé
status-reset-done = Réarmement : le filtre libère la machine
status-diagnosers-reset = Diagnostiqueurs réarmés : les capteurs sont de nouveau lus
status-reset-refused = Réarmement : { $reason }. Toujours refusé ? Vérifiez la machine, puis Réinitialiser…
words-request-on = { $id } EN MARCHE
words-request-off = { $id } À L'ARRÊT
words-request-off-meaning = { $id } À L'ARRÊT ({ $meaning })
words-request-refused = { $what } refusé : { $why }
words-with = , avec { $values }
status-export-cancelled = Export annulé (pas de boîte d'enregistrement sur ce bureau ? Le bouton Exporter à côté écrit dans le dossier de données)

## Alarmes des marches précédentes (l'historique)
past-title = Alarmes des marches précédentes (historique)
past-count = { $n ->
    [one] { $n } alarme
   *[other] { $n } alarmes
} sur les { $days } derniers jours, toutes les sessions de ce dossier de données (console et passerelle), les plus récentes d'abord, telles qu'enregistrées

## Types d'alarme (filtre de l'historique)
kind-safety-filter-trip = arrêt sécurité du filtre
kind-diagnosis = diagnostic
kind-task-monitor = surveillance des tâches
kind-live-link = liaison
kind-specification-error = erreur de spécification
kind-hazard = danger
kind-implausible-sensor = capteur invraisemblable
kind-program-divergence = programme divergent
syn-elevator-left = Élévateur gauche
syn-elevator-right = Élévateur droit

## Panneau de la liaison
linkp-title = Liaison
linkp-mode-gateway = Mode : passerelle (filtre appliqué entre l'automate et la machine)
linkp-mode-monitor = Mode : surveillance (lecture seule, le filtre signale)
linkp-stopped-error = Liaison : arrêtée ({ $error })
linkp-stopped = Liaison : arrêtée
linkp-connected = Liaison : connectée à { $peer }
linkp-connecting = Liaison : connexion à { $peer }
linkp-reconnecting = Liaison : reconnexion à { $peer } (tentative { $attempt }, prochaine dans { $ms } ms)
linkp-last-poll = Dernière lecture : il y a { $ms } ms
linkp-never-polled = Dernière lecture : jamais
linkp-no-stale = Entrées périmées : aucune
linkp-stale = Entrées périmées : { $inputs }
linkp-cycles = Cycles : { $n }
linkp-protocol = Protocole : { $protocol }
linkp-plc-protocol = Côté automate : { $protocol }
linkp-exceptions = Exceptions : { $n } (erreurs de transport { $errors }, connexions { $connections })
linkp-plc-server = Serveur pour l'automate : { $address }
linkp-plc-heard = Automate : entendu
linkp-plc-silent = Automate : muet
linkp-plc-refused = Requêtes de l'automate refusées : { $n }
linkp-safe-outputs = Sorties sûres : { $reason }
linkp-dropped = { $n } cycles non montrés (la console a pris du retard)
linkp-status = { $poll } · { $stale } · { $cycles } cycles · { $exceptions } exceptions

## Rapport d'incident
report-nobody = personne de connecté
report-date = Exporté le : { $date }
report-user = Utilisateur : { $user } (rôle { $role })
report-plant = Machine : { $name } (dossier `{ $folder }`)
report-program = Programme : { $name }, version `{ $version }`
report-program-exercise = Programme : exercice { $id } (variante de « { $name } »), version `{ $version }`
report-run = Marche : { $title }
report-filter = Mode du filtre : { $mode }
report-vigie = Vigie { $version }
report-chronogram = Chronogramme de la fenêtre de l'arrêt
report-chronogram-screen = Le chronogramme tel qu'il était à l'écran (les lignes et la fenêtre choisies par l'utilisateur) :
report-chronogram-legend = Noir : capteurs lus · bleu : sorties appliquées · orange : le filtre a appliqué une autre valeur que la commande · violet : observateurs · rouge : l'arrêt
report-title = Rapport d'incident
report-trip = Arrêt sécurité à **{ $time_ms } ms** (cycle { $cycle })
report-constraint = Contrainte **{ $id }** : `{ $source }` — { $notation }
report-fallback = Repli : { $outputs }
report-trace = Trace avant l'arrêt (changements)
report-time-ms = temps ms
report-changes = changements
syn-predicted = prévu : caisse %box% %kind%
syn-hazard-sheared = cisaillée
syn-hazard-dropped = tombée
syn-hazard-collision = heurtée
syn-hazard-pushedagainststopped = poussée contre un arrêt
syn-hazard-endstop = entraîné contre sa butée
syn-hazard-opposeddrives = entraîné dans les deux sens à la fois
syn-hazard-declared = état dangereux
syn-hazard-overflow = débordement
syn-hazard-dryrun = pompe à sec
syn-predicted-component = prévu : %kind%
