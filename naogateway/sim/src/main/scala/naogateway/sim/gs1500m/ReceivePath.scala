package naogateway.sim.gs1500m

import scala.annotation.tailrec

/** A datagram the peer puts on air at simulated time `at` (nanoseconds), towards the robot. */
final case class Scheduled(at: Long, datagram: AirDatagram)

/** A discrete-event driver of the robot's receive path in simulated time: the peer's datagrams reach the module at
  * their scheduled times while the firmware loop runs, both in time order (on a tie the datagram is in the module
  * before the firmware polls). Pure: the same inputs always give the same run.
  *
  * For interactive protocols (where the robot's replies shape what the peer sends next) drive [[Gs1500mModule.arrive]]
  * and [[Cm530Firmware.act]] directly, the same way.
  */
object ReceivePath {

  /** Everything a run produced. */
  final case class Run(
      module: Gs1500mModule,
      firmware: Cm530Firmware,
      firmwareEvents: Vector[FirmwareEvent],
      moduleEvents: Vector[ModuleEvent]
  ) {

    /** The datagrams the firmware got, in order, with when. */
    def received: Vector[FirmwareEvent.Received] = firmwareEvents.collect { case r: FirmwareEvent.Received => r }
  }

  /** Runs until every scheduled datagram has arrived and the firmware's next action lies after `until`. */
  def run(schedule: Seq[Scheduled], module: Gs1500mModule, firmware: Cm530Firmware, until: Long): Run = {
    val firmwareEvents = Vector.newBuilder[FirmwareEvent]
    val moduleEvents = Vector.newBuilder[ModuleEvent]

    @tailrec
    def loop(pending: List[Scheduled], m: Gs1500mModule, f: Cm530Firmware): (Gs1500mModule, Cm530Firmware) =
      pending match {
        case next :: rest if next.at <= f.nextActionAt || f.nextActionAt > until =>
          val step = m.arrive(next.datagram, next.at)
          moduleEvents ++= step.events
          loop(rest, step.module, f)
        case _ if f.nextActionAt <= until =>
          val step = f.act(m)
          firmwareEvents ++= step.events
          moduleEvents ++= step.moduleEvents
          loop(pending, step.module, step.firmware)
        case _ => (m, f)
      }

    val (m, f) = loop(schedule.sortBy(_.at).toList, module, firmware)
    val last = m.advance(until)
    moduleEvents ++= last.events
    Run(last.module, f, firmwareEvents.result(), moduleEvents.result())
  }
}
