# Les éléments des explications en français, un message par code stable
# (core/src/explain/codes.md), à partir des champs de l'élément. En anglais, la console
# montre le texte que le cœur a écrit (l'enregistrement). Un test vérifie que chaque
# code du tableau a ici son message.

## Niveau 0 — état courant
explain-X001 = Le filtre de sécurité a arrêté la machine à { $time_ms } ms : { $constraints } aurai{ $n_constraints ->
    [one] t
   *[other] ent
} été violée{ $n_constraints ->
    [one] {""}
   *[other] s
}.
explain-X002 = { $reasons ->
    [none] { $output } est maintenu EN MARCHE.
   *[other] { $output } est maintenu EN MARCHE par le filtre : { $reasons }.
}
explain-X003 = Arrêtés : { $outputs }.
# X004 recorded before X005 existed could name an observer: such records still read right.
explain-X004 = { $observer ->
    [none] { $output } À L'ARRÊT : { $meaning }.
   *[other] L'observateur { $observer } est à 1 : une caisse qu'aucun capteur ne voit est déduite.
}
explain-X005 = L'observateur { $observer } est à 1 : une caisse qu'aucun capteur ne voit est déduite.
explain-X006 = Mode surveillance : à { $time_ms } ms, { $constraints } est devenue vraie ; en mode appliqué, le filtre de sécurité aurait arrêté la machine. Le filtre signale seulement : les sorties de l'automate n'ont pas été modifiées.
explain-X007 = En mode appliqué, le filtre aurait maintenu EN MARCHE : { $held } ; arrêté : { $stopped }.

## Niveau 1 — projection
explain-X101 = Sans le filtre, { $after_ms } ms plus tard : la caisse { $box } { $kind ->
    [Sheared] serait cisaillée au niveau
    [Dropped] tomberait
    [Collision] heurterait une autre caisse au niveau
   *[other] serait poussée contre une surface arrêtée au niveau
} de : { $place } ({ $elements }).
explain-X104 = Sans le filtre, { $after_ms } ms plus tard : { $place_kind ->
    [danger] { $place }.
   *[other] { $place } { $kind ->
        [EndStop] serait entraîné contre la butée de sa course
        [OpposedDrives] serait entraîné dans les deux sens à la fois
        [Overflow] déborderait
        [DryRun] ferait tourner une pompe à sec
       *[other] serait dans un état dangereux
    } ({ $elements }).
}
explain-X102 = Sans le filtre, aucun dommage n'est prévu dans les { $horizon_ms } ms qui suivent : l'arrêt a empêché une situation interdite.
explain-X103 = Mode surveillance : la machine continuant, aucun dommage n'est prévu dans les { $horizon_ms } ms ; la violation reste une situation que les contraintes interdisent.

## Niveau 2 — avant l'arrêt
explain-X201 = { $multi ->
    [yes] { $constraint } : son terme { $term } est devenu vrai : { $values }.
   *[other] { $constraint } = { $notation } est devenue vraie : { $values }.
}
explain-X202 = { $meaning ->
    [none] Le filtre a maintenu EN MARCHE { $output } (commandé À L'ARRÊT).
   *[other] Le filtre a maintenu EN MARCHE { $output } (commandé À L'ARRÊT ; { $output } À L'ARRÊT : { $meaning }).
}
explain-X203 = Le filtre a forcé À L'ARRÊT { $output } (commandé EN MARCHE).

## Niveau 3 — avancé
explain-X301 = { $signal } est passé de { $from } à { $to } à { $time_ms } ms ({ $ms_before ->
    [0] dans le cycle de l'arrêt
   *[other] { $ms_before } ms avant l'arrêt
}){ $in_constraint ->
    [true] , élément de la contrainte
   *[other] {""}
}.
explain-X302 = { $output } reste EN MARCHE.

## Niveau 4 — hypothèse
explain-X401 = { $sensor } est passé de { $from } à { $to } dans le cycle de l'arrêt et fait partie de { $constraint } ; la commande n'a pas fait l'évolution que ce changement demande : { $expected }.
explain-X402 = { $sensor } a changé dans le même cycle que { $actuators } ; { $sensor } ne fait pas partie de { $constraint } : une réceptivité ou une équation de sortie qui lit { $sensor } a pu commander l'actionneur.
explain-X403 = Attendu de la commande : { $expected }.
explain-X404 = { $actuators } alors qu'aucune entrée n'a changé : une temporisation ou une mémoire interne du programme l'a probablement commandé.
explain-X405 = L'observateur { $observers } a changé sans changement direct d'une entrée ; la contrainte est devenue vraie par lui.
explain-X406 = Les cycles d'avant l'arrêt ne sont plus dans l'historique : pas d'hypothèse.
explain-X407 = La transition { $transition } (réceptivité `{ $receptivity }`) a été franchie { $ms_before ->
    [0] dans le cycle de l'arrêt
   *[other] { $ms_before } ms avant l'arrêt
} et a désactivé l'étape { $step } ({ $qualifier } { $output }) ; les étapes activées ({ $activated }) ne commandent pas { $output } : la réceptivité de { $transition } est suspecte (elle lit { $signals }).
explain-X408 = La transition { $transition } (réceptivité `{ $receptivity }`) a été franchie { $ms_before ->
    [0] dans le cycle de l'arrêt
   *[other] { $ms_before } ms avant l'arrêt
} et a activé l'étape { $step }, dont l'action { $qualifier } { $output } commande { $output } : la réceptivité de { $transition } est suspecte (elle lit { $signals }).
explain-X409 = Le qualificatif { $qualifier } de l'action de l'étape { $step } sur { $output } fait la différence : il est suspect.
explain-X410 = L'équation de { $output } (`{ $expression }`) commande la valeur interdite ({ $signals }) ; les transitions qui ont changé en dernier les étapes qu'elle lit : { $transitions }.
explain-X411 = { $output } devrait être EN MARCHE mais rien dans le programme ne le commande : les étapes qui agissent sur lui ({ $steps }) sont inactives et son équation est fausse.
explain-X412 = L'étape { $step } est active et son action { $qualifier } { $output } commande { $output } ; les transitions qui la quittent, { $transition } (`{ $receptivity }`), n'ont pas été franchies : leur réceptivité est suspecte (elles lisent { $signals }).
explain-X413 = Contrainte combinée { $constraint } : l'étape { $step }, activée dans le cycle de l'arrêt, commande { $driven } alors que { $output }, que la contrainte exige avec lui, n'est commandé par rien : les actions de la nouvelle étape ou ce qui commande { $output } l'oublient.
explain-X418 = { $sensor } est passé de { $from } à { $to } au cycle d'arrêt alors que la physique de la machine ne l'attendait pas (seulement quand { $expected } : { $follows }) : aucune pièce ne pouvait l'atteindre. Sa lecture, ou le capteur qui aurait dû annoncer la pièce, est le premier suspect : vérifiez { $sensor } sur la machine avant le programme.
explain-X417 = L'action { $qualifier } { $output } de l'étape { $step } commande { $output } dans la situation où { $constraint } l'interdit ({ $condition }) : { $evidence ->
    [entry] l'étape a été activée dans le cycle de l'arrêt par { $activated_by }, dont la réceptivité `{ $receptivity }` exige cette situation
    [exits] les transitions qui la quittent, { $exits } (`{ $receptivity }`), attendent la fin de cette situation
   *[other] c'est une étape initiale qui commande { $output } dès le premier cycle, aucune transition ne l'a activée
}. L'action de { $step } sur { $output } est suspecte : elle appartient à une autre étape.
explain-X414 = { $sensor } est suspect : sa lecture a fait un front que la physique de la machine ne permet pas ; l'étage de plausibilité garde sa dernière valeur plausible et { $constraint } la lit comme pouvant valoir l'une ou l'autre. Vérifiez { $sensor } (cellule, réflecteur, câble) avant le programme.
explain-X415 = Matériel d'abord : le diagnostiqueur { $component } a trouvé un défaut certain à { $time_ms } ms ({ $descriptions }). Vérifiez { $check } sur la machine avant le programme : les suspects du programme ci-dessous supposent que la machine a obéi à ses ordres.
explain-X416 = Matériel d'abord : le diagnostiqueur { $component } tient le composant pour défaillant à { $time_ms } ms sans pouvoir choisir entre { $descriptions }. Vérifiez { $check } sur la machine avant le programme : les suspects du programme ci-dessous supposent que la machine a obéi à ses ordres.
explain-X419 = { $state ->
    [welded] Matériel d'abord : { $actuator } a été relâché et son contact miroir { $mirror } le lit toujours fermé ({ $constraint }) : son contacteur est soudé. Vérifiez le contacteur de { $actuator } sur la machine ; le programme l'a relâché.
   *[dead] Matériel d'abord : { $actuator } a été commandé et son contact miroir { $mirror } le lit ouvert ({ $constraint }) : il ne s'est pas fermé (bobine, fusible, câblage ou contacteur). Vérifiez { $actuator } sur la machine ; le programme l'a commandé.
}
explain-X420 = { $kind ->
    [step] L'étape { $element } est dans la POU { $pou } de { $file }, ligne { $line }, colonne { $column }.
    [transition] La transition { $element } est dans la POU { $pou } de { $file }, ligne { $line }, colonne { $column }.
   *[other] { $element } est écrit dans la POU { $pou } ({ $kind }) de { $file }, ligne { $line }, colonne { $column }.
}

## Alarmes (le texte du cœur reste l'enregistrement ; en français, à partir du code et
## des champs de l'alarme)
alarm-program-divergence = l'automate n'exécute pas le programme donné ({ $name }, version { $version }) : { $output } est à { $plc } dans l'automate, à { $program } dans le programme
alarm-plausibility-suspect = { $sensor } ({ $description }) suspect : { $edge ->
    [rise] montée
   *[fall] retombée
} invraisemblable (la physique de la machine ne le permet pas maintenant) ; { $sensor } tenu à { $held }{ $latched ->
    [true] {" "}jusqu'à ce qu'il relise { $held } (si tôt après le dernier front, le dernier était un parasite)
   *[other] {""}
}
alarm-plausibility-filtered = { $sensor } ({ $description }) : { $edge ->
    [rise] une montée
   *[fall] une retombée
} de { $ms } ms filtrée (plus courte que sa confirmation de { $confirm_ms } ms)
alarm-plausibility-again = { $sensor } ({ $description }) de nouveau plausible après { $ms } ms
alarm-diagnosis-sensor-estimated = { $estimate ->
    [true] Diagnostic : défaut { $fault } du capteur { $sensor } ({ $description }) (certain) : { $sensor } est estimé à partir des intervalles de temps (la temporisation de { $component }) ; la production continue en mode dégradé
   *[other] Diagnostic : défaut { $fault } du capteur { $sensor } ({ $description }) (certain) : les contraintes lisent { $sensor } estimé à partir des intervalles de temps (la temporisation de { $component }), le programme lit toujours { $sensor }
}
alarm-diagnosis-sensor-no-estimate = Diagnostic : défaut { $fault } du capteur { $sensor } ({ $description }) (certain) ; { $sensor } n'a pas d'estimation dans le modèle { $component } : les contraintes et le programme lisent toujours { $sensor }
alarm-diagnosis-actuator = { $stop ->
    [true] Diagnostic : défaut { $fault } sur { $partition } ({ $component }), certain : partition d'actionneur en défaut, tout le système est arrêté
   *[other] Diagnostic : défaut { $fault } sur { $partition } ({ $component }), certain : partition d'actionneur en défaut ; le filtre ne fait que signaler, le système n'est pas arrêté
}
alarm-diagnosis-ambiguous = { $stop ->
    [true] Diagnostic : { $component } est en défaut, sans pouvoir trancher entre { $fault } : { $partition } (un entraînement) peut être en cause, tout le système est arrêté du côté sûr ; vérifiez-le, puis réarmez les diagnostiqueurs
   *[other] Diagnostic : { $component } est en défaut, sans pouvoir trancher entre { $fault } : { $partition } (un entraînement) peut être en cause ; le filtre ne fait que signaler, le système n'est pas arrêté
}
alarm-diagnosis-other = Diagnostic : { $fault } sur { $partition } ({ $component })
alarm-hazard = { $kind ->
    [EndStop] { $place } : entraîné contre la butée de sa course
    [OpposedDrives] { $place } : entraîné dans les deux sens à la fois
    [Declared] État dangereux : { $place }
    [Overflow] { $place } déborde
    [DryRun] { $place } : une pompe tourne à sec
   *[other] Caisse { $item } endommagée : { $kind ->
        [Sheared] cisaillée au niveau de : { $place }
        [Dropped] tombée de : { $place }
        [Collision] heurt au niveau de : { $place }
       *[other] poussée contre une surface arrêtée : { $place }
    }
}
alarm-action = Action { $action } ({ $initial } → { $final } sous { $command }) : { $kind ->
    [early] état final atteint après { $elapsed_ms } ms, avant T_MIN = { $t_min_ms } ms
    [late] état final non atteint à T_MAX = { $t_max_ms } ms
   *[other] état final apparu sans action validée
}
alarm-task = { $subject } : { $code ->
    [T001] arrêtée trop longtemps, elle ne peut plus finir à temps
    [T002] plus lente que la normale
    [T003] pas finie dans son temps acceptable
    [T004] finie plus tôt que possible (un capteur ou une étape manquée ?)
    [T005] finie hors de son temps acceptable
    [T006] la commande a manqué sa fenêtre de temps
    [T007] un événement est venu alors qu'aucun n'était attendu
   *[T008] deux tâches désynchronisées
}

## Journal : les entrées du cœur (en anglais, le texte enregistré)
journal-trip = arrêt sécurité sur { $constraints }
journal-reset = réarmement du filtre par l'opérateur
journal-reinitialise = réinitialisation par l'opérateur après vérification de la machine : { $emptied ->
    [true] machine vidée, chaque observateur repart vide
   *[other] pièces laissées en place, observateurs effacés là où les capteurs ne laissent pas de place à leur pièce
}, programme à ses étapes initiales, arrêt terminé
journal-plant-emptied = l'opérateur a retiré { $n } pièce(s) de la machine
journal-repair = réparation sur le simulateur : { $n } défaut(s) retiré(s)
journal-manual-on = mode manuel : le programme n'est plus exécuté, les sorties restent en l'état ; chaque commande est vérifiée par les contraintes de sécurité
journal-manual-off = mode automatique : le programme repart de ses étapes initiales ; appuyez sur Départ cycle
journal-by-hand = { $output } { $on ->
    [true] EN MARCHE
   *[other] À L'ARRÊT
} à la main
journal-bypass = { $constraint } dérivée pendant { $minutes } min par { $by } : { $reason }
journal-bypass-end = { $constraint } de nouveau appliquée (dérivation terminée)
journal-bypass-expired = { $constraint } de nouveau appliquée (durée de la dérivation écoulée)
journal-operator = { $action ->
    [Start] Départ cycle
    [Stop] Arrêt
    [Pause] Pause
   *[other] Reprise
}
journal-fault = défaut injecté : { $what }
journal-plausible-again = { $sensor } de nouveau plausible

## Journal : la nature d'une entrée
journal-kind-trip = arrêt
journal-kind-reset = réarmement
journal-kind-reset_refused = réarm. refusé
journal-kind-operator = opérateur
journal-kind-session = session
journal-kind-hazard = dommage
journal-kind-fault = défaut
journal-kind-manual = manuel
journal-kind-manual_refused = man. refusé
journal-kind-bypass = dérivation
journal-kind-bypass_end = fin dériv.
journal-kind-ack = acquit
journal-kind-shelve = masquage
journal-kind-unshelve = démasquage
journal-kind-login = connexion
journal-kind-logout = déconnexion
journal-kind-diagnosis = diagnostic
journal-kind-plausibility = plausibilité
journal-kind-task_alarm = tâche
journal-kind-task_warning = tâche (avert.)
journal-kind-reinitialise = réinit.
journal-kind-plant_emptied = vidage
journal-kind-maintenance = maintenance
journal-kind-training = formation
journal-kind-report = rapport
