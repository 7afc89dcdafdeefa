/* firmware/port/stm32/stm32.h: the few Cortex-M3 and STM32F1 registers the boards touch. UART5 has the same
 * address, layout and interrupt on the CM-530's STM32F103 and on qemu's netduino2 (STM32F205). */
#ifndef STM32_H
#define STM32_H

#include <stdint.h>

#define REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* SysTick and the NVIC (ARMv7-M) */
#define SYST_CSR REG32(0xE000E010u)
#define SYST_RVR REG32(0xE000E014u)
#define SYST_CVR REG32(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CORE_CLOCK (1u << 2)
#define NVIC_ISER(n) REG32(0xE000E100u + 4u * (n))
#define SCB_VTOR REG32(0xE000ED08u)
#define SCB_AIRCR REG32(0xE000ED0Cu)

/* UART5: the CM-530's "ZigBee" port, where the GS1500M sits (TX PC12, RX PD2) */
#define UART5_BASE 0x40005000u
#define UART5_SR REG32(UART5_BASE + 0x00u)
#define UART5_DR REG32(UART5_BASE + 0x04u)
#define UART5_BRR REG32(UART5_BASE + 0x08u)
#define UART5_CR1 REG32(UART5_BASE + 0x0Cu)
#define USART_SR_ORE (1u << 3)
#define USART_SR_RXNE (1u << 5)
#define USART_SR_TXE (1u << 7)
#define USART_SR_TC (1u << 6)
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR1_UE (1u << 13)
#define UART5_IRQ 53u

static inline void irq_enable(uint32_t irq) { NVIC_ISER(irq / 32u) = 1u << (irq % 32u); }
static inline void cpu_irq_disable(void) { __asm__ volatile("cpsid i" ::: "memory"); }
static inline void cpu_irq_enable(void) { __asm__ volatile("cpsie i" ::: "memory"); }
static inline void cpu_wfi(void) { __asm__ volatile("wfi" ::: "memory"); }

#endif
