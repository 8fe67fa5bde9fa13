package org.pocketbot.desktop

/** Placeholder until the Compose Desktop control panel lands. */
internal const val MODULE_NAME: String = "pocketbot-desktop-app"
